// The project's MSH reader (msh_reader.hpp): every format Gmsh writes read back as written, MSH
// 4.0 binary, MSH 2.2 physical groups per element, skipped sections, and the refusals with
// their section and line or byte; mesh files that are scripts or not regular files.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include "cdem/core/error.hpp"
#include "mesh_test_files.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/msh_reader.hpp"
#include "cdem/mesh/structured.hpp"

namespace cdem {
namespace {

namespace fs = std::filesystem;

using testing_files::data;
fs::path scratch_dir() { return testing_files::scratch_dir("cdem_msh_"); }

// The MeshError message of reading `text`, or "" when it reads.
std::string error_of(const std::string& text) {
  try {
    (void)read_msh(text, "mesh file 'm.msh'");
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

// The same mesh; vertices to the last digits ASCII keeps (Gmsh writes 16 significant digits).
// `same_order`: the same element order and tags (MSH 2.2: Gmsh's writer renumbers the elements
// entity by entity, so only the set of elements is the same).
void expect_same(const Mesh& a, const Mesh& b, bool same_order) {
  ASSERT_EQ(a.dim, b.dim);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(a.vertices[i][k], b.vertices[i][k], 1e-15 * (1 + std::abs(a.vertices[i][k])))
          << "vertex " << i;
  ASSERT_EQ(a.region_names, b.region_names);
  if (same_order) {
    ASSERT_EQ(a.elem_type, b.elem_type);
    ASSERT_EQ(a.elem_vertices, b.elem_vertices);
    ASSERT_EQ(a.elem_region, b.elem_region);
    ASSERT_EQ(a.elem_tag, b.elem_tag);
  } else {
    auto elements = [](const Mesh& m) {
      std::vector<std::tuple<int, std::array<std::int32_t, 4>, std::int32_t>> e;
      for (std::size_t i = 0; i < m.num_elements(); ++i)
        e.emplace_back(static_cast<int>(m.elem_type[i]), m.elem_vertices[i], m.elem_region[i]);
      std::sort(e.begin(), e.end());
      return e;
    };
    ASSERT_EQ(elements(a), elements(b));
  }
  ASSERT_EQ(a.face_sets.size(), b.face_sets.size());
  for (std::size_t i = 0; i < a.face_sets.size(); ++i) {
    EXPECT_EQ(a.face_sets[i].name, b.face_sets[i].name);
    ASSERT_EQ(a.face_sets[i].facets.size(), b.face_sets[i].facets.size());
    auto facets = [](const FaceSet& f) {
      std::vector<std::array<std::int32_t, 3>> v;
      for (const Facet& x : f.facets) v.push_back(x.v);
      std::sort(v.begin(), v.end());
      return v;
    };
    EXPECT_EQ(facets(a.face_sets[i]), facets(b.face_sets[i]));
  }
}

// A valid MSH 2.2 square of four triangles with "rock" and the "bottom" edge; `nodes` and
// `elements` replace the sections' bodies when given.
std::string square_v22(const std::string& nodes = "", const std::string& elements = "") {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 3 \"bottom\"\n2 5 "
         "\"rock\"\n$EndPhysicalNames\n$Nodes\n" +
         (nodes.empty() ? "5\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n" : nodes) +
         "$EndNodes\n$Elements\n" +
         (elements.empty() ? "5\n1 1 2 3 1 1 2\n5 2 2 5 1 1 2 5\n6 2 2 5 1 2 3 5\n7 2 2 5 1 3 4 5\n"
                             "8 2 2 5 1 4 1 5\n"
                           : elements) +
         "$EndElements\n";
}

// ---------------------------------------------------------------------------------------------
// Formats

// Every format libgmsh 4.8 writes (2.2 and 4.1 ASCII and binary, 4.0 ASCII) gives the generated
// mesh back; MSH 2.2 renumbers the elements 1..n (Gmsh's writer), the others keep the tags.
TEST(MshReader, EveryFormatGmshWritesReadsBack) {
  const fs::path dir = scratch_dir();
  for (const GenerateSpec& s : testing_files::round_trip_specs(0.25)) {
    const Mesh m = generate_mesh(s);
    for (double version : {2.2, 4.0, 4.1})
      for (bool binary : {false, true}) {
        if (version == 4.0 && binary) continue;  // Gmsh 4.8 writes 4.0 in ASCII only
        const std::string path =
            (dir / (s.shape + std::to_string(version) + (binary ? "b" : "a") + ".msh")).string();
        write_gmsh(m, path, version, binary);
        SCOPED_TRACE(path);
        expect_same(m, read_gmsh(path), version != 2.2);
      }
  }
  fs::remove_all(dir);
}

TEST(MshReader, Msh40BinarySameAsAscii) {
  const Mesh a = read_gmsh(data("slot_v40.msh"));
  const Mesh b = read_gmsh(data("slot_binary_v40.msh"));
  expect_same(a, b, true);
  EXPECT_EQ(a.region_names, (std::vector<std::string>{"rock", "charge"}));
  EXPECT_EQ(a.face_sets.size(), 5u);
}

// MSH 2.2 gives the physical group per element: Gmsh writes an element in two groups twice with
// the same tag. It is one element, in the first (lowest) group; its other group is empty then.
TEST(MshReader, Msh22ElementWrittenOncePerGroupIsOneElement) {
  const std::string mesh = square_v22(
      "",
      "6\n1 1 2 3 1 1 2\n5 2 2 5 1 1 2 5\n5 2 2 7 1 1 2 5\n6 2 2 5 1 2 3 5\n7 2 2 5 1 3 4 5\n"
      "8 2 2 7 2 4 1 5\n");
  const Mesh m = read_msh(mesh, "m");
  ASSERT_EQ(m.num_elements(), 4u);
  EXPECT_EQ(m.elem_tag, (std::vector<std::int64_t>{5, 6, 7, 8}));
  // Groups 5 "rock" and 7 (unnamed): element 5 is in both (rock wins), element 8 only in 7.
  EXPECT_EQ(m.region_names, (std::vector<std::string>{"rock", "7"}));
  EXPECT_EQ(m.elem_region, (std::vector<std::int32_t>{0, 0, 0, 1}));
}

TEST(MshReader, Msh22SameTagForOtherNodesIsAnError) {
  const std::string msg = error_of(square_v22(
      "",
      "5\n1 1 2 3 1 1 2\n5 2 2 5 1 1 2 5\n5 2 2 5 1 2 3 5\n7 2 2 5 1 3 4 5\n8 2 2 5 1 4 1 5\n"));
  EXPECT_NE(msg.find("element tag 5 is used twice"), std::string::npos) << msg;
  EXPECT_NE(msg.find("$Elements, line 20"), std::string::npos) << msg;
  EXPECT_NE(msg.find("$Elements, line 21"), std::string::npos) << msg;
}

TEST(MshReader, SkipsOtherSectionsAndReadsParametricNodes) {
  const std::string mesh =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nanything $Nodes\n$EndComments\n"
      "$Entities\n0 0 1 0\n1 0 0 0 1 1 0 1 1 0\n$EndEntities\n"
      "$Nodes\n1 4 1 4\n2 1 1 4\n1\n2\n3\n4\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n"
      "$EndNodes\n$Elements\n1 2 1 2\n2 1 2 2\n1 1 2 3\n2 1 3 4\n$EndElements\n"
      "$NodeData\n1\n\"u\"\n1\n0.0\n3\n0\n1\n1\n1 0.1\n$EndNodeData\n";
  const Mesh m = read_msh(mesh, "m");
  EXPECT_EQ(m.num_elements(), 2u);
  EXPECT_EQ(m.region_names, (std::vector<std::string>{"1"}));
}

// Numbers as C's scanf (hence Gmsh) reads them: a leading '+' is accepted.
TEST(MshReader, LeadingPlusSigns) {
  const Mesh m =
      read_msh(square_v22("5\n+1 +0 0 0\n2 1.0e+00 0 0\n3 +1 +1 0\n4 0 1 0\n5 0.5 0.5 0\n"), "m");
  EXPECT_EQ(m.num_elements(), 4u);
  EXPECT_NE(error_of(square_v22("5\n1 +-1 0 0\n")).find("found '+-1'"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Refusals: the file, the section and the line or byte.

TEST(MshReaderErrors, NotMshAtAll) {
  for (const char* text : {"", "Point(1) = {0, 0, 0};\n", "SystemCall \"ls\";\n", "\xff\xfe"}) {
    const std::string msg = error_of(text);
    EXPECT_NE(msg.find("mesh file 'm.msh': line 1: not a Gmsh MSH file"), std::string::npos) << msg;
  }
  EXPECT_NE(error_of("$NOD\n1\n1 0 0 0\n$ENDNOD\n").find("MSH version 1 is not supported"),
            std::string::npos);
}

TEST(MshReaderErrors, FormatLine) {
  auto with = [](const std::string& line) {
    return error_of("$MeshFormat\n" + line + "\n$EndMeshFormat\n");
  };
  EXPECT_NE(with("3.0 0 8").find("$MeshFormat, line 2: MSH version '3.0' is not supported"),
            std::string::npos);
  EXPECT_NE(with("4.1 2 8").find("file-type '2'"), std::string::npos);
  EXPECT_NE(with("4.1 0 4").find("data-size '4'"), std::string::npos);
  EXPECT_NE(with("4.1 0").find("expected 'version file-type data-size'"), std::string::npos);
  const std::string big_endian =
      "$MeshFormat\n4.1 1 8\n" + std::string("\0\0\0\1", 4) + "\n$EndMeshFormat\n";
  EXPECT_NE(error_of(big_endian).find("big-endian"), std::string::npos);
}

TEST(MshReaderErrors, CountsLargerThanTheFileAreRefusedBeforeAllocating) {
  // 1e18 nodes (8e18 bytes of memory if believed) in a 200-byte file.
  std::string msg = error_of(square_v22("1000000000000000000\n1 0 0 0\n"));
  EXPECT_NE(msg.find("$Nodes, line 10: number of nodes 1000000000000000000: more than the rest of "
                     "the file"),
            std::string::npos)
      << msg;
  msg = error_of(square_v22("", "18446744073709551615\n"));
  EXPECT_NE(msg.find("number of elements 18446744073709551615"), std::string::npos) << msg;
  msg = error_of(square_v22("", "1\n1 2 2147483647 1 1 1 1 1\n"));
  EXPECT_NE(msg.find("number of tags 2147483647"), std::string::npos) << msg;
}

TEST(MshReaderErrors, TruncatedAndOverlongSections) {
  std::string msg = error_of(square_v22("5\n1 0 0 0\n2 1 0 0\n"));
  EXPECT_NE(msg.find("$Nodes, line 13: expected a node tag (a whole number), found '$EndNodes'"),
            std::string::npos)
      << msg;
  msg = error_of(square_v22("1\n1 0 0 0\n2 1 0 0\n"));
  EXPECT_NE(msg.find("$Nodes, line 12: expected $EndNodes, found '2'"), std::string::npos) << msg;
  msg = error_of("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n0 0 0 0\n");
  EXPECT_NE(msg.find("the file ends before $EndNodes"), std::string::npos) << msg;
  msg = error_of("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nno end\n");
  EXPECT_NE(msg.find("section $Comments has no $EndComments"), std::string::npos) << msg;
  msg = error_of(square_v22() + "$Nodes\n0\n$EndNodes\n");
  EXPECT_NE(msg.find("a second $Nodes section"), std::string::npos) << msg;
  msg = error_of("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n0\n$EndNodes\n");
  EXPECT_NE(msg.find("no $Elements section"), std::string::npos) << msg;
}

TEST(MshReaderErrors, BinaryDataCutShortNamesTheByte) {
  const std::string full = [] {
    std::ifstream f(data("mixed_binary_v41.msh"), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  const std::size_t nodes = full.find("$Nodes\n") + 7;
  const std::string msg = error_of(full.substr(0, nodes + 40));
  EXPECT_NE(msg.find("$Nodes, byte"), std::string::npos) << msg;
  // Every prefix of the file is refused cleanly.
  for (std::size_t n = 0; n + 16 < full.size(); n += 7)
    EXPECT_FALSE(error_of(full.substr(0, n)).empty()) << n;
}

TEST(MshReaderErrors, BadNumbersAndTags) {
  std::string msg = error_of(square_v22("5\n1 0 0 0\n2 x 0 0\n3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n"));
  EXPECT_NE(msg.find("$Nodes, line 12: expected a node coordinate (a number), found 'x'"),
            std::string::npos)
      << msg;
  msg = error_of(square_v22("5\n1 0 0 0\n0 1 0 0\n3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n"));
  EXPECT_NE(msg.find("node tag 0 is out of range (tags start at 1)"), std::string::npos) << msg;
  msg = error_of(square_v22("5\n1 0 0 0\n2 inf 0 0\n3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n"));
  EXPECT_NE(msg.find("node 2: coordinate x = inf is not a finite number"), std::string::npos)
      << msg;
  msg = error_of(square_v22("5\n1 0 0 0\n2 1 -2e7 0\n3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n"));
  EXPECT_NE(msg.find("node 2: coordinate y = -2e+07 is beyond +-1e+07"), std::string::npos) << msg;
  msg = error_of(square_v22("", "1\n1 200 2 0 1 1 2\n"));
  EXPECT_NE(msg.find("$Elements, line 19: unknown element type 200"), std::string::npos) << msg;
  msg = error_of(square_v22("", "1\n1 34 2 0 1 1 2\n"));
  EXPECT_NE(msg.find("'Polygon' (Gmsh type 34) has a variable number of nodes"), std::string::npos)
      << msg;
  msg = error_of(square_v22("", "1\n1 2 2 5 1 1 2 9\n"));
  EXPECT_NE(msg.find("element 1 ($Elements, line 19): node 9 is not defined"), std::string::npos)
      << msg;
}

TEST(MshReaderErrors, PhysicalNames) {
  auto names = [](const std::string& body) {
    return error_of("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n" + body +
                    "$EndPhysicalNames\n");
  };
  EXPECT_NE(names("1\n2 5 rock\n").find("expected a name in double quotes"), std::string::npos);
  EXPECT_NE(names("1\n2 5 \"rock\n").find("the name has no closing quote"), std::string::npos);
  EXPECT_NE(names("1\n2 5 \"ro\xffk\"\n").find("its name holds invalid UTF-8"), std::string::npos);
  EXPECT_NE(names("1\n7 5 \"rock\"\n").find("physical dimension 7"), std::string::npos);
  EXPECT_NE(names("1000000\n").find("number of physical names 1000000"), std::string::npos);
}

TEST(MshReaderErrors, Msh4Structure) {
  const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string nodes = "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";
  std::string msg = error_of(head + nodes + "$Elements\n1 1 1 1\n3 1 2 1\n1 1 2 3\n$EndElements\n");
  EXPECT_NE(msg.find("'Triangle 3' elements (dimension 2) on an entity of dimension 3"),
            std::string::npos)
      << msg;
  msg = error_of(head + nodes + "$Elements\n1 2 1 2\n2 1 2 2\n4 1 2 3\n4 3 2 1\n$EndElements\n");
  EXPECT_NE(msg.find("element tag 4 is used twice"), std::string::npos) << msg;
  msg = error_of(head + nodes + "$Elements\n1 1 1 1\n2 1 2 5\n1 1 2 3\n$EndElements\n");
  EXPECT_NE(msg.find("element block 1 holds 5 elements, more than the 1 the header has left"),
            std::string::npos)
      << msg;
  msg = error_of(head + "$Nodes\n1 2 1 2\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n");
  EXPECT_NE(msg.find("node block 1 holds 3 nodes, more than the 2 the header has left"),
            std::string::npos)
      << msg;
  msg = error_of(head + "$PartitionedEntities\n$EndPartitionedEntities\n");
  EXPECT_NE(msg.find("partitioned meshes are not supported"), std::string::npos) << msg;
  msg = error_of(head + "$Entities\n0 0 2 0\n1 0 0 0 1 1 0 0 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n");
  EXPECT_NE(msg.find("entity 1 of dimension 2 is listed twice"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------------------------
// Files: never interpreted, regular files only.

TEST(ReadGmshFiles, AScriptIsRefusedAndNotRun) {
  const fs::path dir = scratch_dir();
  const fs::path marker = dir / "pwned";
  for (const char* name : {"script.msh", "script.geo"}) {
    {
      std::ofstream f(dir / name);
      f << "SystemCall \"touch " << marker.string() << "\";\n";
    }
    std::string msg;
    try {
      (void)read_gmsh((dir / name).string());
    } catch (const MeshError& e) {
      msg = e.what();
    }
    EXPECT_NE(msg.find("not a Gmsh MSH file"), std::string::npos) << msg;
    EXPECT_FALSE(fs::exists(marker)) << "the script ran";
  }
  fs::remove_all(dir);
}

TEST(ReadGmshFiles, OnlyRegularFiles) {
  const fs::path dir = scratch_dir();
  ASSERT_EQ(::mkfifo((dir / "fifo.msh").c_str(), 0600), 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "character device"},
      {(dir / "fifo.msh").string(), "FIFO"},
      {dir.string(), "directory"},
  };
  for (const auto& [path, why] : cases) {
    std::string msg;
    try {
      (void)read_gmsh(path);
    } catch (const MeshError& e) {
      msg = e.what();
    }
    EXPECT_NE(msg.find("cannot open mesh file '" + path + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find(why), std::string::npos) << msg;
  }
  fs::remove_all(dir);
}

// A vertex far away: its elements are reported as such, not a sound element as degenerate.
TEST(CheckMesh, AnElementBillionsOfTimesTheMedianIsReported) {
  Mesh m = structured_grid_2d(100, 100, 0.001, false);  // triangles of 5e-7 m^2
  m.vertices[0].x = 9.9e6;
  std::string msg;
  try {
    check_mesh(m, "mesh 'far'");
  } catch (const MeshError& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("times the median element's"), std::string::npos) << msg;
  EXPECT_NE(msg.find("a misplaced vertex?"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("degenerate"), std::string::npos) << msg;
}

}  // namespace
}  // namespace cdem
