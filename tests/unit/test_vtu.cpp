// VTU/PVD writer and reader: exact round trips (plain and zlib), the on-disk layout VTK
// expects, atomic writes, and rejection of truncated, inconsistent or unwritable files.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cdem/io/vtu.hpp"
#include "cdem/io/vtu_reader.hpp"

namespace cdem {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards.
class VtuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("cdem_vtu_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void spit(const std::string& path, const std::string& bytes) {
  fs::remove(path);  // a new file: rewriting in place makes ext4 flush on every close
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Index of the first byte of the appended data (just after the '_' marker).
std::size_t data_start(const std::string& text) {
  return text.find('_', text.find("<AppendedData")) + 1;
}

std::uint64_t bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

VtuArray f64_array(std::string name, int components, std::size_t n, double seed) {
  VtuArray a{std::move(name), components, {}, {}};
  for (std::size_t i = 0; i < n * static_cast<std::size_t>(components); ++i)
    a.f64.push_back(seed + static_cast<double>(i) / 3.0 - 1e-7 * static_cast<double>(i * i));
  return a;
}

// Two triangles, a quad and a tetrahedron over 7 points, with 1-, 3- and 6-component
// doubles and integers on points and cells (special doubles included, compared by bits).
VtuMesh mixed_mesh() {
  VtuMesh m;
  m.points = {
      {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 0, 0}, {2, 1, 0}, {0.25, 0.25, 1.0 / 3}};
  m.connectivity = {0, 1, 2, 1, 3, 2, 1, 4, 5, 3, 0, 1, 2, 6};
  m.offsets = {3, 6, 10, 14};
  m.types = {kVtkTriangle, kVtkTriangle, kVtkQuad, kVtkTetra};
  m.point_data.push_back(f64_array("displacement", 3, 7, 0.1));
  m.point_data.push_back(f64_array("pressure", 1, 7, -2e6));
  m.point_data.push_back(f64_array("stress", 6, 7, 1e-300));
  m.point_data.push_back({"node_id",
                          1,
                          {},
                          {0, -1, 2, std::numeric_limits<std::int32_t>::max(),
                           std::numeric_limits<std::int32_t>::min(), 5, 6}});
  VtuArray damage{"damage & <mode> \"x\"", 1, {0.0, -0.0, 1.0, 0.5}, {}};
  damage.f64[2] = std::numeric_limits<double>::quiet_NaN();
  damage.f64[3] = -std::numeric_limits<double>::infinity();
  m.cell_data.push_back(damage);
  m.cell_data.push_back({"damage_mode", 1, {}, {0, 1, 2, 1}});
  m.cell_data.push_back(f64_array("stress", 6, 4, 3.5));
  m.cell_data.push_back(f64_array("velocity", 3, 4, 1e300));
  return m;
}

void expect_same(const VtuMesh& m, const VtuData& d) {
  ASSERT_EQ(d.num_points, static_cast<std::int64_t>(m.points.size()));
  ASSERT_EQ(d.num_cells, static_cast<std::int64_t>(m.types.size()));
  ASSERT_EQ(d.points.size(), m.points.size());
  for (std::size_t i = 0; i < m.points.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(bits(d.points[i][k]), bits(m.points[i][k])) << i;
  EXPECT_EQ(d.connectivity, m.connectivity);
  EXPECT_EQ(d.offsets, m.offsets);
  EXPECT_EQ(d.types, m.types);
  const auto same = [](const std::vector<VtuArray>& want,
                       const std::map<std::string, VtuArray>& got) {
    ASSERT_EQ(got.size(), want.size());
    for (const VtuArray& a : want) {
      SCOPED_TRACE(a.name);
      ASSERT_TRUE(got.count(a.name));
      const VtuArray& b = got.at(a.name);
      EXPECT_EQ(b.components, a.components);
      EXPECT_EQ(b.i32, a.i32);
      ASSERT_EQ(b.f64.size(), a.f64.size());
      for (std::size_t i = 0; i < a.f64.size(); ++i) EXPECT_EQ(bits(b.f64[i]), bits(a.f64[i]));
    }
  };
  same(m.point_data, d.point_data);
  same(m.cell_data, d.cell_data);
}

TEST_F(VtuTest, MixedMeshRoundTripsExactly) {
  const VtuMesh m = mixed_mesh();
  for (bool compress : {false, true}) {
    SCOPED_TRACE(compress);
    const std::string path = file(compress ? "z.vtu" : "raw.vtu");
    write_vtu(path, m, compress);
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    const VtuData d = read_vtu(path);
    EXPECT_EQ(d.compressed, compress);
    expect_same(m, d);
  }
}

TEST_F(VtuTest, LargeArraysCrossZlibBlocks) {
  // 131072 doubles = exactly one 1 MiB block (the header's last-block size is then 0);
  // 60001 3-vectors span two blocks with a partial last one.
  for (std::size_t n : {std::size_t{131072}, std::size_t{60001}}) {
    VtuMesh m;
    for (std::size_t i = 0; i < n; ++i) {
      const double x = static_cast<double>(i);
      m.points.push_back({std::sin(x), std::cos(x), x * 1e-3});
      m.connectivity.push_back(static_cast<std::int64_t>(i));
      m.offsets.push_back(static_cast<std::int64_t>(i + 1));
      m.types.push_back(kVtkVertex);
    }
    m.point_data.push_back(f64_array("scalar", 1, n, 1.0));
    m.point_data.push_back(f64_array("vector", 3, n, 2.0));
    m.cell_data.push_back({"id", 1, {}, std::vector<std::int32_t>(n, 7)});
    for (bool compress : {false, true}) {
      const std::string path = file("big.vtu");
      write_vtu(path, m, compress);
      expect_same(m, read_vtu(path));
    }
  }
}

TEST_F(VtuTest, EmptyMeshRoundTrips) {
  VtuMesh m;
  m.point_data.push_back({"p", 1, {}, {}});
  m.cell_data.push_back({"c", 3, {}, {}});
  for (bool compress : {false, true}) {
    write_vtu(file("empty.vtu"), m, compress);
    const VtuData d = read_vtu(file("empty.vtu"));
    EXPECT_EQ(d.num_points, 0);
    EXPECT_EQ(d.num_cells, 0);
    EXPECT_EQ(d.point_data.at("p").f64.size(), 0u);
    EXPECT_EQ(d.cell_data.at("c").components, 3);
  }
}

// The layout VTK's reader expects, checked on the bytes without the project's reader.
TEST_F(VtuTest, LayoutFollowsVtkXmlAppendedRaw) {
  VtuMesh m = mixed_mesh();
  m.point_data.erase(m.point_data.begin() + 1, m.point_data.end());  // displacement first
  for (bool compress : {false, true}) {
    const std::string path = file("layout.vtu");
    write_vtu(path, m, compress);
    const std::string text = slurp(path);
    const std::string head = text.substr(0, data_start(text));
    EXPECT_EQ(text.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version="
                         "\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"",
                         0),
              0u);
    EXPECT_EQ(head.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos, compress);
    EXPECT_NE(head.find("<Piece NumberOfPoints=\"7\" NumberOfCells=\"4\">"), std::string::npos);
    EXPECT_NE(head.find("<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents="
                        "\"3\" format=\"appended\" offset=\"0\"/>"),
              std::string::npos);
    EXPECT_NE(head.find("Name=\"damage &amp; &lt;mode&gt; &quot;x&quot;\""), std::string::npos);
    EXPECT_NE(head.find("<DataArray type=\"Int32\" Name=\"damage_mode\""), std::string::npos);
    EXPECT_NE(head.find("<DataArray type=\"Int64\" Name=\"connectivity\""), std::string::npos);
    EXPECT_NE(head.find("<DataArray type=\"Int64\" Name=\"offsets\""), std::string::npos);
    EXPECT_NE(head.find("<DataArray type=\"UInt8\" Name=\"types\""), std::string::npos);
    EXPECT_NE(head.find("<AppendedData encoding=\"raw\">"), std::string::npos);
    const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
    EXPECT_EQ(text.substr(text.size() - tail.size()), tail);

    // The first array (displacement, offset 0) right after '_'.
    const auto* p = reinterpret_cast<const unsigned char*>(text.data()) + data_start(text);
    const std::vector<double>& want = m.point_data[0].f64;
    const std::uint64_t nbytes = want.size() * sizeof(double);
    std::vector<double> got(want.size());
    std::uint64_t h[4];
    std::memcpy(h, p, sizeof h);
    if (!compress) {
      EXPECT_EQ(h[0], nbytes);
      std::memcpy(got.data(), p + 8, nbytes);
    } else {
      EXPECT_EQ(h[0], 1u);        // one block
      EXPECT_EQ(h[1], 1u << 20);  // block size
      EXPECT_EQ(h[2], nbytes);    // partial last block
      uLongf out = static_cast<uLongf>(nbytes);
      ASSERT_EQ(
          uncompress(reinterpret_cast<Bytef*>(got.data()), &out, p + 32, static_cast<uLong>(h[3])),
          Z_OK);
      EXPECT_EQ(out, nbytes);
    }
    EXPECT_EQ(got, want);
  }
}

// ParaView-facing metadata: tensor component names, the TimeValue field data, and an
// integer array's type kept on a mesh without cells (the empty-grid placeholder).
TEST_F(VtuTest, TensorsAreNamedAndTheTimeIsInTheFile) {
  VtuMesh m = mixed_mesh();
  m.time = 2.5e-3 + 1e-19;
  m.cell_data[0].component_names = {};  // 1 component: no names
  for (bool compress : {false, true}) {
    const std::string path = file("named.vtu");
    write_vtu(path, m, compress);
    const std::string text = slurp(path);
    const std::string head = text.substr(0, data_start(text));
    EXPECT_NE(head.find(R"(Name="stress" NumberOfComponents="6" format="appended")"),
              std::string::npos);
    EXPECT_NE(head.find(R"(ComponentName0="xx" ComponentName1="yy" ComponentName2="zz" )"
                        R"(ComponentName3="xy" ComponentName4="yz" ComponentName5="xz"/>)"),
              std::string::npos);
    EXPECT_EQ(head.find(R"(Name="displacement" NumberOfComponents="3" format="appended" )"
                        R"(offset="0" ComponentName)"),
              std::string::npos);
    const std::size_t fd = head.find("<FieldData>");
    ASSERT_NE(fd, std::string::npos);
    EXPECT_LT(head.find("<UnstructuredGrid>"), fd);
    EXPECT_LT(fd, head.find("<Piece"));
    EXPECT_NE(head.find(R"(<DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" )"
                        R"(format="appended")"),
              std::string::npos);
    const VtuData d = read_vtu(path);
    expect_same(m, d);
    EXPECT_EQ(bits(d.time), bits(m.time));
    EXPECT_EQ(d.cell_data.at("stress").component_names,
              (std::vector<std::string>{"xx", "yy", "zz", "xy", "yz", "xz"}));
    EXPECT_TRUE(d.cell_data.at("velocity").component_names.empty());
    EXPECT_EQ(d.cell_data.at("damage_mode").type, VtuType::kInt32);
    EXPECT_EQ(d.cell_data.at("stress").type, VtuType::kFloat64);
  }
  // Without a time: no field data.
  VtuMesh untimed = mixed_mesh();
  write_vtu(file("untimed.vtu"), untimed);
  EXPECT_EQ(slurp(file("untimed.vtu")).find("FieldData"), std::string::npos);
  EXPECT_TRUE(std::isnan(read_vtu(file("untimed.vtu")).time));
}

TEST_F(VtuTest, EmptyMeshKeepsArrayTypesAndReadsAsEmpty) {
  VtuMesh m;
  m.time = 0.0;
  m.cell_data.push_back({"mode", 1, {}, {}, VtuType::kInt32});
  m.cell_data.push_back({"broken_fraction", 1, {}, {}});
  m.cell_data.push_back({"stress", 6, {}, {}});
  for (bool compress : {false, true}) {
    const std::string path = file("empty_typed.vtu");
    write_vtu(path, m, compress);
    const std::string text = slurp(path);
    const std::string head = text.substr(0, data_start(text));
    // One placeholder cell (a polygon of no nodes, see vtu.hpp) and no point.
    EXPECT_NE(head.find(R"(<Piece NumberOfPoints="0" NumberOfCells="1">)"), std::string::npos);
    EXPECT_NE(head.find(R"(<DataArray type="Int32" Name="mode")"), std::string::npos);
    EXPECT_NE(head.find(R"(<DataArray type="Float64" Name="broken_fraction")"),
              std::string::npos);
    const VtuData d = read_vtu(path);
    EXPECT_EQ(d.num_points, 0);
    EXPECT_EQ(d.num_cells, 0);
    EXPECT_TRUE(d.types.empty());
    EXPECT_TRUE(d.offsets.empty());
    EXPECT_EQ(d.cell_data.at("mode").type, VtuType::kInt32);
    EXPECT_TRUE(d.cell_data.at("mode").i32.empty());
    EXPECT_EQ(d.cell_data.at("broken_fraction").type, VtuType::kFloat64);
    EXPECT_TRUE(d.cell_data.at("stress").f64.empty());
    EXPECT_EQ(d.cell_data.at("stress").components, 6);
    EXPECT_EQ(bits(d.time), bits(0.0));
  }
}

TEST_F(VtuTest, PvdRoundTripsAndStaysValidAfterEachStep) {
  const std::string pvd = file("fields.pvd");
  const std::vector<std::pair<double, std::string>> steps = {
      {0.0, "fields/step_000000.vtu"},
      {1e-5 / 3, "fields/step_000001.vtu"},
      {2.5e-3 + 1e-19, "fields/a&b <c>.vtu"}};
  PvdWriter writer(pvd);
  EXPECT_TRUE(read_pvd(pvd).empty());
  for (std::size_t i = 0; i < steps.size(); ++i) {
    writer.add(steps[i].first, steps[i].second);
    EXPECT_FALSE(fs::exists(pvd + ".tmp"));
    const auto got = read_pvd(pvd);
    ASSERT_EQ(got.size(), i + 1);
    for (std::size_t k = 0; k <= i; ++k) {
      EXPECT_EQ(bits(got[k].first), bits(steps[k].first));  // %.17g round-trips exactly
      EXPECT_EQ(got[k].second, steps[k].second);
    }
  }
  EXPECT_EQ(writer.steps(), steps);
  const std::string text = slurp(pvd);
  EXPECT_NE(text.find("<VTKFile type=\"Collection\" version=\"0.1\""), std::string::npos);
  EXPECT_NE(text.find("<DataSet timestep=\"3.3333333333333337e-06\" group=\"\" part=\"0\" "
                      "file=\"fields/step_000001.vtu\"/>"),
            std::string::npos);
  EXPECT_THROW(writer.add(std::nan(""), "x.vtu"), std::invalid_argument);
  EXPECT_EQ(read_pvd(pvd).size(), 3u);
}

// Expects `f` to throw std::runtime_error whose message contains every string of `parts`.
template <class F>
void expect_error(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "'" << e.what() << "' lacks '" << part << "'";
  }
}

TEST_F(VtuTest, TruncatedFilesAreRejected) {
  for (bool compress : {false, true}) {
    SCOPED_TRACE(compress);
    const std::string path = file("full.vtu"), cut = file("cut.vtu");
    write_vtu(path, mixed_mesh(), compress);
    const std::string text = slurp(path);
    // Every cut but the final newline breaks the file.
    for (std::size_t n = 0; n + 1 < text.size(); ++n) {
      spit(cut, text.substr(0, n));
      expect_error([&] { read_vtu(cut); }, {cut});
    }
    spit(cut, text.substr(0, text.size() - 1));
    EXPECT_NO_THROW(read_vtu(cut));
    // A cut inside the binary data says so.
    spit(cut, text.substr(0, data_start(text) + 40));
    expect_error([&] { read_vtu(cut); }, {cut, "past the end of the file (truncated?)"});
    spit(cut, text.substr(0, text.size() - 12));
    expect_error([&] { read_vtu(cut); }, {cut, "ends inside <", "truncated"});
  }
}

TEST_F(VtuTest, WrongArrayLengthsAreRejected) {
  for (bool compress : {false, true}) {
    SCOPED_TRACE(compress);
    const std::string path = file("a.vtu"), bad = file("bad.vtu");
    write_vtu(path, mixed_mesh(), compress);
    const std::string text = slurp(path);
    const auto edit = [&](const std::string& from, const std::string& to) {
      std::string t = text;
      const std::size_t at = t.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      t.replace(at, from.size(), to);
      spit(bad, t);
    };
    // One point more than the arrays hold.
    edit("NumberOfPoints=\"7\"", "NumberOfPoints=\"8\"");
    expect_error([&] { read_vtu(bad); },
                 {bad, "point array 'displacement'", "holds 168 bytes, expected 192"});
    // An array declared with fewer components than written.
    edit("Name=\"displacement\" NumberOfComponents=\"3\"",
         "Name=\"displacement\" NumberOfComponents=\"2\"");
    expect_error([&] { read_vtu(bad); }, {bad, "holds 168 bytes, expected 112"});
    // One cell fewer.
    edit("NumberOfCells=\"4\"", "NumberOfCells=\"3\"");
    expect_error([&] { read_vtu(bad); }, {bad, "cell array", "expected"});
    // Not the file kind, not the XML the writer writes.
    edit("</Points>", "</Pointz>");
    expect_error([&] { read_vtu(bad); }, {bad, "end tag </Pointz> where </Points> was expected"});
    edit("type=\"UnstructuredGrid\"", "type=\"PolyData\"");
    expect_error([&] { read_vtu(bad); }, {bad, "expected UnstructuredGrid"});
  }
}

TEST_F(VtuTest, CorruptZlibDataIsRejected) {
  const std::string path = file("z.vtu");
  write_vtu(path, mixed_mesh(), true);
  std::string text = slurp(path);
  text[data_start(text) + 32 + 2] ^= 0x5a;  // inside the first zlib block
  spit(path, text);
  expect_error([&] { read_vtu(path); }, {path, "point array 'displacement'", "zlib block 1 of 1"});
}

TEST_F(VtuTest, AnyFlippedByteIsReadOrRejectedCleanly) {
  for (bool compress : {false, true}) {
    const std::string path = file("ok.vtu"), bad = file("flip.vtu");
    write_vtu(path, mixed_mesh(), compress);
    const std::string text = slurp(path);
    for (std::size_t i = 0; i < text.size(); i += 3) {
      std::string t = text;
      t[i] = static_cast<char>(t[i] ^ 0xff);
      spit(bad, t);
      try {
        read_vtu(bad);  // a flip inside the values still reads
      } catch (const std::runtime_error&) {
      }
    }
  }
}

TEST_F(VtuTest, InconsistentMeshesAreRefusedAndLeaveNoFile) {
  const std::string path = file("m.vtu");
  const auto refused = [&](const VtuMesh& m, const std::string& why) {
    try {
      write_vtu(path, m);
      ADD_FAILURE() << "accepted: " << why;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".tmp"));
  };
  VtuMesh m = mixed_mesh();
  m.point_data[1].f64.pop_back();
  refused(m, "point array 'pressure': 6 values, expected 7");
  m = mixed_mesh();
  m.cell_data[1].f64 = {1, 2, 3, 4};
  refused(m, "both f64 and i32");
  m = mixed_mesh();
  m.cell_data[3].name = "stress";
  refused(m, "used twice");
  m = mixed_mesh();
  m.connectivity[4] = 7;
  refused(m, "connectivity[4] = 7 is not a point id");
  m = mixed_mesh();
  m.types[0] = kVtkQuad;
  refused(m, "cell 0: VTK type 9 needs 4 nodes, got 3");
  m = mixed_mesh();
  m.cell_data[0].type = VtuType::kInt32;
  refused(m, "declared Int32, given doubles");
  m = mixed_mesh();
  m.cell_data[1].type = VtuType::kFloat64;
  refused(m, "declared Float64, given integers");
  m = mixed_mesh();
  m.cell_data[2].component_names = {"a", "b"};
  refused(m, "2 component names for 6 components");
}

TEST_F(VtuTest, UnwritablePathsThrowNamingThePath) {
  const std::string path = file("no/such/dir/out.vtu");
  expect_error([&] { write_vtu(path, mixed_mesh()); }, {path});
  const std::string pvd = file("no/such/dir/out.pvd");
  expect_error([&] { PvdWriter w(pvd); }, {pvd});
  expect_error([&] { read_vtu(path); }, {path});
}

TEST_F(VtuTest, RewritingReplacesTheFileWhole) {
  const std::string path = file("r.vtu");
  VtuMesh big = mixed_mesh();
  write_vtu(path, big, false);
  VtuMesh small;
  small.points = {{1, 2, 3}};
  small.connectivity = {0};
  small.offsets = {1};
  small.types = {kVtkVertex};
  write_vtu(path, small, true);
  expect_same(small, read_vtu(path));
}

}  // namespace
}  // namespace cdem
