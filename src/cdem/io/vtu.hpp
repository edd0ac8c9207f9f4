// VTU/PVD output: the project's own writer of VTK XML unstructured grids and time series.
//
// Format choices (readable by ParaView 5.x and VTK >= 6):
//  - One file per output step: VTK XML UnstructuredGrid, version="1.0", one Piece,
//    byte_order="LittleEndian", header_type="UInt64". Every array is stored once, in the
//    <AppendedData encoding="raw"> section after the `_` marker (no base64: smallest, fastest);
//    each DataArray's offset counts bytes from just after `_`.
//  - Uncompressed array: UInt64 byte count, then the bytes. Compressed array
//    (compressor="vtkZLibDataCompressor", zlib level 1 = Z_BEST_SPEED, blocks of 1 MiB
//    compressed in parallel with OpenMP): UInt64 header [nblocks, 1048576, size of the last
//    block if partial else 0, compressed size of each block...], then the zlib streams.
//  - Types: Float64 for doubles and the points, Int32 for integer fields, Int64 for cell
//    connectivity and offsets (end offset of each cell), UInt8 for VTK cell types. An array
//    keeps its declared type (VtuArray::type) even when it holds no value, so every file of a
//    series declares the same type for the same array (an empty crack file included).
//  - Component names: 6-component arrays are the project's symmetric tensors (Sym6) and get
//    ComponentName0..5 = xx, yy, zz, xy, yz, xz, so ParaView shows them by name, not 0..5
//    (VtuArray::component_names overrides this, for any number of components).
//  - Time: when VtuMesh::time is finite, the grid carries it as field data `TimeValue`
//    (Float64, one tuple; VTK's and ParaView's convention), so one file knows its time
//    without the PVD.
//  - Empty grids: a mesh without cells is written with one placeholder cell, a VTK_POLYGON
//    with no nodes, and its cell arrays with one tuple (NaN for Float64, 0 for Int32).
//    VTK's XML reader requires a <Cells> element; meshio (5.x to 7.0) fails on a <Cells> with
//    no cell (IndexError, meshio issue #1412) and on a piece without one; with the
//    placeholder both read the file, and the placeholder draws nothing in ParaView. The
//    project's readers (vtu_reader.hpp, python/cdemblast/vtu.py) recognise it (0-node polygon
//    as the only cell) and return 0 cells.
//  - Files are written to `<path>.tmp` and renamed onto `<path>` (atomic on POSIX), so a
//    reader never sees half a file. No fsync: this guards against a crashed run, not power loss.
//  - A series is a PVD collection (<DataSet timestep part="0" file>, times as %.17g, so they
//    read back bit-exact), rewritten (also atomically) after every step.
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

// The stored type of an array. kAuto: Int32 when i32 holds values, else Float64; give the
// type of an array that may be empty (an integer field on an empty mesh), so that it is
// declared with the same type in every file of a series.
enum class VtuType : std::uint8_t { kAuto, kFloat64, kInt32 };

// One named point or cell array. Exactly one of f64 / i32 holds the values (both may be empty
// for an empty mesh), stored tuple by tuple: size = (number of points or cells) * components.
struct VtuArray {
  std::string name;
  int components = 1;
  std::vector<double> f64;
  std::vector<std::int32_t> i32;
  VtuType type = VtuType::kAuto;
  // Names of the components (written as ComponentName0, 1, ...); empty: xx, yy, zz, xy, yz, xz
  // for 6 components, none otherwise. Otherwise exactly `components` names.
  std::vector<std::string> component_names = {};
};

// VTK cell type codes used by the project (any other VTK code is written unchecked).
enum VtkCellType : std::uint8_t {
  kVtkVertex = 1,
  kVtkLine = 3,
  kVtkTriangle = 5,
  kVtkQuad = 9,
  kVtkTetra = 10,
  kVtkHexahedron = 12,
  kVtkWedge = 13,
  kVtkPyramid = 14,
};

struct VtuMesh {
  std::vector<Vec3> points;
  std::vector<std::int64_t> connectivity;  // flattened cell node ids (0-based)
  std::vector<std::int64_t> offsets;       // end offset of each cell in connectivity (VTK)
  std::vector<std::uint8_t> types;         // VTK cell type of each cell (VtkCellType)
  std::vector<VtuArray> point_data, cell_data;
  // Simulated time of the grid (s), written as the field data TimeValue when finite.
  double time = std::numeric_limits<double>::quiet_NaN();
};

// Writes `mesh` to `path` (see the format above); compress selects the zlib block layout.
// Throws std::invalid_argument when the mesh is inconsistent (sizes, node ids, node counts of
// known cell types, empty or duplicate array names, an array whose values are not of its
// declared type, a wrong number of component names), and std::runtime_error naming the path
// when the file cannot be written; in both cases `path` is left untouched.
void write_vtu(const std::string& path, const VtuMesh& mesh, bool compress = true);

// A time series: each add() appends a step and rewrites the .pvd index at once (atomically),
// so a crashed run leaves a valid series of the steps written so far. The constructor writes
// an empty collection (replacing any old file), which also reports an unwritable path early.
class PvdWriter {
 public:
  // `steps`: entries already in the series (a restarted run continues it). `run_id`, when not
  // empty, is written as an XML comment (cdemblast: run_id ...), so that a reader can tell whose
  // series it is.
  explicit PvdWriter(std::string pvd_path, std::vector<std::pair<double, std::string>> steps = {},
                     std::string run_id = "");
  // `vtu_path` as ParaView should resolve it: relative to the directory of the .pvd file.
  // Throws std::invalid_argument for a non-finite time, std::runtime_error on I/O failure.
  void add(double time, const std::string& vtu_path);

  const std::string& path() const { return path_; }
  const std::vector<std::pair<double, std::string>>& steps() const { return steps_; }

 private:
  void rewrite() const;
  std::string path_;
  std::vector<std::pair<double, std::string>> steps_;
  std::string run_id_;
};

}  // namespace cdem
