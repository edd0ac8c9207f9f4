// VTK XML UnstructuredGrid (.vtu) and collection (.pvd) writers; the format is described in
// vtu.hpp. The XML header is formatted first (offsets need every array's encoded size), then
// the arrays are streamed: uncompressed ones straight from the caller's vectors, compressed
// ones from 1 MiB zlib blocks compressed in parallel beforehand.
#include "cdem/io/vtu.hpp"

#include "cdem/io/atomic_file.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
#include <stdexcept>
#include <type_traits>

namespace cdem {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the VTU writer stores native bytes and declares LittleEndian");
static_assert(std::is_standard_layout_v<Vec3> && sizeof(Vec3) == 3 * sizeof(double),
              "points are written straight from the Vec3 array");

constexpr std::uint64_t kBlockSize = std::uint64_t{1} << 20;  // uncompressed zlib block
constexpr int kZlibLevel = 1;                                 // Z_BEST_SPEED

// Escapes a string for an XML attribute value in double quotes.
std::string xml_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

bool has_control_char(const std::string& s) {
  return std::any_of(s.begin(), s.end(),
                     [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

// Number of nodes of the fixed-size VTK cell types, 0 for any other type.
int nodes_of_cell_type(std::uint8_t type) {
  switch (type) {
    case kVtkVertex:
      return 1;
    case kVtkLine:
      return 2;
    case kVtkTriangle:
      return 3;
    case kVtkQuad:
      return 4;
    case kVtkTetra:
      return 4;
    case kVtkHexahedron:
      return 8;
    case kVtkWedge:
      return 6;
    case kVtkPyramid:
      return 5;
    default:
      return 0;
  }
}

void check_arrays(const std::string& path, const std::vector<VtuArray>& arrays, std::size_t n,
                  const char* where) {
  std::set<std::string> names;
  for (const VtuArray& a : arrays) {
    const auto bad = [&](const std::string& what) {
      return std::invalid_argument(
          fmt::format("write_vtu('{}'): {} array '{}': {}", path, where, a.name, what));
    };
    if (a.name.empty() || has_control_char(a.name))
      throw bad("the name must be non-empty and without control characters");
    if (!names.insert(a.name).second) throw bad("the name is used twice");
    if (a.components < 1) throw bad(fmt::format("{} components (at least 1)", a.components));
    if (!a.f64.empty() && !a.i32.empty()) throw bad("both f64 and i32 values are set");
    if (a.type == VtuType::kInt32 && !a.f64.empty()) throw bad("declared Int32, given doubles");
    if (a.type == VtuType::kFloat64 && !a.i32.empty()) throw bad("declared Float64, given integers");
    if (!a.component_names.empty() &&
        a.component_names.size() != static_cast<std::size_t>(a.components))
      throw bad(fmt::format("{} component names for {} components", a.component_names.size(),
                            a.components));
    for (const std::string& c : a.component_names)
      if (c.empty() || has_control_char(c))
        throw bad("component names must be non-empty and without control characters");
    const std::size_t size = a.i32.empty() ? a.f64.size() : a.i32.size();
    const std::size_t expected = n * static_cast<std::size_t>(a.components);
    if (size != expected)
      throw bad(fmt::format("{} values, expected {} ({} {}s x {} components)", size, expected, n,
                            where, a.components));
  }
}

void check_mesh(const std::string& path, const VtuMesh& mesh) {
  const auto bad = [&](const std::string& what) {
    return std::invalid_argument(fmt::format("write_vtu('{}'): {}", path, what));
  };
  const std::size_t ncells = mesh.types.size();
  if (mesh.offsets.size() != ncells)
    throw bad(fmt::format("{} cell offsets for {} cell types", mesh.offsets.size(), ncells));
  std::int64_t begin = 0;
  for (std::size_t c = 0; c < ncells; ++c) {
    const std::int64_t end = mesh.offsets[c];
    if (end < begin || end > static_cast<std::int64_t>(mesh.connectivity.size()))
      throw bad(fmt::format("cell {}: end offset {} outside [{}, {}]", c, end, begin,
                            mesh.connectivity.size()));
    const int nodes = nodes_of_cell_type(mesh.types[c]);
    if (nodes > 0 && end - begin != nodes)
      throw bad(fmt::format("cell {}: VTK type {} needs {} nodes, got {}", c, mesh.types[c], nodes,
                            end - begin));
    begin = end;
  }
  if (begin != static_cast<std::int64_t>(mesh.connectivity.size()))
    throw bad(fmt::format("the cells use {} connectivity entries of {}", begin,
                          mesh.connectivity.size()));
  const auto npoints = static_cast<std::int64_t>(mesh.points.size());
  for (std::size_t i = 0; i < mesh.connectivity.size(); ++i)
    if (mesh.connectivity[i] < 0 || mesh.connectivity[i] >= npoints)
      throw bad(fmt::format("connectivity[{}] = {} is not a point id (there are {} points)", i,
                            mesh.connectivity[i], npoints));
  check_arrays(path, mesh.point_data, mesh.points.size(), "point");
  check_arrays(path, mesh.cell_data, ncells, "cell");
}

// Names of the components written for an array (see vtu.hpp): the given ones, else
// xx, yy, zz, xy, yz, xz for the 6-component symmetric tensors, else none.
std::vector<std::string> component_names(const VtuArray& a) {
  if (!a.component_names.empty()) return a.component_names;
  if (a.components == 6) return {"xx", "yy", "zz", "xy", "yz", "xz"};
  return {};
}

bool is_int32(const VtuArray& a) {
  return a.type == VtuType::kInt32 || (a.type == VtuType::kAuto && !a.i32.empty());
}

// One array of the appended section: its XML description and its encoded bytes.
struct Appended {
  std::string xml_type, name;
  int components = 1;
  std::vector<std::string> component_names;
  std::string extra;  // further attributes (NumberOfTuples of field data)
  const char* raw = nullptr;  // the caller's values, raw_size bytes
  std::uint64_t raw_size = 0;
  std::vector<std::uint64_t> header;               // compressed: [n, block, last, sizes...]
  std::vector<std::vector<unsigned char>> blocks;  // compressed blocks

  std::uint64_t encoded_size(bool compress) const {
    if (!compress) return sizeof(std::uint64_t) + raw_size;
    std::uint64_t size = header.size() * sizeof(std::uint64_t);
    for (const auto& b : blocks) size += b.size();
    return size;
  }
};

template <class T>
Appended appended(std::string xml_type, std::string name, int components,
                  const std::vector<T>& values) {
  Appended a;
  a.xml_type = std::move(xml_type);
  a.name = std::move(name);
  a.components = components;
  a.raw = reinterpret_cast<const char*>(values.data());
  a.raw_size = values.size() * sizeof(T);
  return a;
}

Appended appended_data(const VtuArray& array) {
  Appended a = is_int32(array) ? appended("Int32", array.name, array.components, array.i32)
                               : appended("Float64", array.name, array.components, array.f64);
  a.component_names = component_names(array);
  return a;
}

// The arrays of a mesh without cells, padded to the placeholder cell's one tuple (NaN for
// Float64, 0 for Int32; see vtu.hpp).
std::vector<VtuArray> placeholder_cell_data(const std::vector<VtuArray>& arrays) {
  std::vector<VtuArray> out = arrays;
  for (VtuArray& a : out) {
    const auto n = static_cast<std::size_t>(a.components);
    if (is_int32(a)) {
      a.type = VtuType::kInt32;
      a.i32.assign(n, 0);
    } else {
      a.type = VtuType::kFloat64;
      a.f64.assign(n, std::numeric_limits<double>::quiet_NaN());
    }
  }
  return out;
}

// Compresses every array into 1 MiB zlib blocks, all blocks in parallel.
void compress_all(const std::string& path, std::vector<Appended>& arrays) {
  struct Task {
    Appended* array;
    std::size_t block;
  };
  std::vector<Task> tasks;
  for (Appended& a : arrays) {
    const std::uint64_t nblocks = (a.raw_size + kBlockSize - 1) / kBlockSize;
    a.header = {nblocks, kBlockSize, a.raw_size % kBlockSize};
    a.header.resize(3 + nblocks, 0);
    a.blocks.resize(nblocks);
    for (std::size_t b = 0; b < nblocks; ++b) tasks.push_back({&a, b});
  }
  const auto ntasks = static_cast<std::int64_t>(tasks.size());
  int failures = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : failures) if (ntasks > 1)
  for (std::int64_t t = 0; t < ntasks; ++t) {
    Appended& a = *tasks[t].array;
    const std::size_t b = tasks[t].block;
    const std::uint64_t begin = b * kBlockSize;
    const std::uint64_t size = std::min(kBlockSize, a.raw_size - begin);
    std::vector<unsigned char>& out = a.blocks[b];
    try {  // no exception may leave an OpenMP region
      out.resize(compressBound(static_cast<uLong>(size)));
    } catch (...) {
      ++failures;
      continue;
    }
    uLongf out_size = static_cast<uLongf>(out.size());
    if (compress2(out.data(), &out_size, reinterpret_cast<const Bytef*>(a.raw + begin),
                  static_cast<uLong>(size), kZlibLevel) != Z_OK) {
      ++failures;
      continue;
    }
    out.resize(out_size);  // shrinking never throws
    a.header[3 + b] = out_size;
  }
  if (failures > 0)
    throw std::runtime_error(fmt::format("cannot write '{}': zlib compression failed", path));
}

std::string data_array_xml(const Appended& a, std::uint64_t offset, const char* indent) {
  std::string xml =
      fmt::format(R"({}<DataArray type="{}" Name="{}")", indent, a.xml_type, xml_escape(a.name));
  if (a.components != 1) xml += fmt::format(R"( NumberOfComponents="{}")", a.components);
  xml += a.extra;
  xml += fmt::format(R"( format="appended" offset="{}")", offset);
  for (std::size_t c = 0; c < a.component_names.size(); ++c)
    xml += fmt::format(R"( ComponentName{}="{}")", c, xml_escape(a.component_names[c]));
  xml += "/>";
  xml += '\n';
  return xml;
}

}  // namespace

void write_vtu(const std::string& path, const VtuMesh& mesh, bool compress) {
  check_mesh(path, mesh);

  // A mesh without cells gets the placeholder cell (see vtu.hpp): a polygon of no nodes.
  const bool placeholder = mesh.types.empty();
  static const std::vector<std::int64_t> kPlaceholderOffsets = {0};
  static const std::vector<std::uint8_t> kPlaceholderTypes = {7};  // VTK_POLYGON
  const std::vector<VtuArray> padded =
      placeholder ? placeholder_cell_data(mesh.cell_data) : std::vector<VtuArray>{};
  const std::vector<VtuArray>& cell_data = placeholder ? padded : mesh.cell_data;
  const std::vector<std::int64_t>& cell_offsets = placeholder ? kPlaceholderOffsets : mesh.offsets;
  const std::vector<std::uint8_t>& cell_types = placeholder ? kPlaceholderTypes : mesh.types;
  const std::vector<double> time_value = {mesh.time};
  const bool has_time = std::isfinite(mesh.time);

  // The appended arrays in file order: point data, cell data, points, cells, field data.
  std::vector<Appended> arrays;
  for (const VtuArray& a : mesh.point_data) arrays.push_back(appended_data(a));
  for (const VtuArray& a : cell_data) arrays.push_back(appended_data(a));
  Appended points;
  points.xml_type = "Float64";
  points.name = "Points";
  points.components = 3;
  points.raw = reinterpret_cast<const char*>(mesh.points.data());
  points.raw_size = mesh.points.size() * sizeof(Vec3);
  arrays.push_back(points);
  arrays.push_back(appended("Int64", "connectivity", 1, mesh.connectivity));
  arrays.push_back(appended("Int64", "offsets", 1, cell_offsets));
  arrays.push_back(appended("UInt8", "types", 1, cell_types));
  if (has_time) {
    arrays.push_back(appended("Float64", "TimeValue", 1, time_value));
    arrays.back().extra = R"( NumberOfTuples="1")";
  }
  if (compress) compress_all(path, arrays);

  std::vector<std::uint64_t> offsets(arrays.size());
  std::uint64_t offset = 0;
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    offsets[i] = offset;
    offset += arrays[i].encoded_size(compress);
  }

  std::string xml = R"(<?xml version="1.0"?>)"
                    "\n";
  xml += R"(<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian")"
         R"( header_type="UInt64")";
  if (compress) xml += R"( compressor="vtkZLibDataCompressor")";
  xml += ">\n  <UnstructuredGrid>\n";
  const char* ind = "        ";
  const std::size_t ncells_array = arrays.size() - (has_time ? 1 : 0);  // end of the cell arrays
  if (has_time) {
    xml += "    <FieldData>\n";
    xml += data_array_xml(arrays.back(), offsets.back(), "      ");
    xml += "    </FieldData>\n";
  }
  xml += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", mesh.points.size(),
                     cell_types.size());
  const std::size_t npd = mesh.point_data.size(), ncd = cell_data.size();
  xml += "      <PointData>\n";
  for (std::size_t i = 0; i < npd; ++i) xml += data_array_xml(arrays[i], offsets[i], ind);
  xml += "      </PointData>\n      <CellData>\n";
  for (std::size_t i = npd; i < npd + ncd; ++i) xml += data_array_xml(arrays[i], offsets[i], ind);
  xml += "      </CellData>\n      <Points>\n";
  std::size_t i = npd + ncd;
  xml += data_array_xml(arrays[i], offsets[i], ind);
  xml += "      </Points>\n      <Cells>\n";
  for (++i; i < ncells_array; ++i) xml += data_array_xml(arrays[i], offsets[i], ind);
  xml += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  xml += "  <AppendedData encoding=\"raw\">\n   _";

  AtomicFile file(path);
  file.write(xml);
  for (const Appended& a : arrays) {
    if (compress) {
      file.write(a.header.data(), a.header.size() * sizeof(std::uint64_t));
      for (const auto& b : a.blocks) file.write(b.data(), b.size());
    } else {
      file.write(&a.raw_size, sizeof(std::uint64_t));
      file.write(a.raw, a.raw_size);
    }
  }
  file.write("\n  </AppendedData>\n</VTKFile>\n");
  file.commit();
}

PvdWriter::PvdWriter(std::string pvd_path, std::vector<std::pair<double, std::string>> steps,
                     std::string run_id)
    : path_(std::move(pvd_path)), steps_(std::move(steps)), run_id_(std::move(run_id)) {
  if (has_control_char(run_id_) || run_id_.find("--") != std::string::npos)
    throw std::invalid_argument(fmt::format("PvdWriter('{}'): a run id without control characters and '--'", path_));
  rewrite();
}

void PvdWriter::add(double time, const std::string& vtu_path) {
  if (!std::isfinite(time))
    throw std::invalid_argument(
        fmt::format("PvdWriter('{}'): time {} of '{}' is not finite", path_, time, vtu_path));
  if (vtu_path.empty() || has_control_char(vtu_path))
    throw std::invalid_argument(fmt::format(
        "PvdWriter('{}'): the file name must be non-empty and without control characters", path_));
  steps_.emplace_back(time, vtu_path);
  try {
    rewrite();
  } catch (...) {
    steps_.pop_back();
    throw;
  }
}

void PvdWriter::rewrite() const {
  std::string xml = R"(<?xml version="1.0"?>)"
                    "\n";
  xml += R"(<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">)"
         "\n";
  if (!run_id_.empty()) xml += fmt::format("  <!-- cdemblast: run_id {} -->\n", run_id_);
  xml += "  <Collection>\n";
  for (const auto& [time, file] : steps_)
    xml += fmt::format(R"(    <DataSet timestep="{:.17g}" group="" part="0" file="{}"/>)"
                       "\n",
                       time, xml_escape(file));
  xml += "  </Collection>\n</VTKFile>\n";
  AtomicFile out(path_);
  out.write(xml);
  out.commit();
}

}  // namespace cdem
