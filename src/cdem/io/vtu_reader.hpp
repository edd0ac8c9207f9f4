// Reader of the VTU and PVD files written by vtu.hpp, for tests and tools. It reads VTK XML
// UnstructuredGrid files with one Piece and every array in a raw <AppendedData> section
// (UInt32 or UInt64 headers, with or without vtkZLibDataCompressor), and checks them: a well
// formed XML head (VTKFile root, UnstructuredGrid, Piece with NumberOfPoints/NumberOfCells),
// every array's decoded length against NumberOfPoints or NumberOfCells times its components,
// and the cells against the points. Any defect throws std::runtime_error naming the file.
// It also reads <FieldData> arrays of the grid (the writer's TimeValue), and returns a grid
// written with the empty-grid placeholder (vtu.hpp: one 0-node polygon, no point) as 0 cells.
#pragma once
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/io/vtu.hpp"

namespace cdem {

struct VtuData {
  std::int64_t num_points = 0, num_cells = 0;
  bool compressed = false;  // the file declared compressor="vtkZLibDataCompressor"
  std::vector<Vec3> points;
  std::vector<std::int64_t> connectivity;  // flattened cell node ids
  std::vector<std::int64_t> offsets;       // end offset of each cell
  std::vector<std::uint8_t> types;         // VTK cell types
  // Arrays by name. Float32/Float64 arrays fill f64; integer arrays fill i32 (values must fit).
  // Arrays by name; their `type` says how the file stored them (Float32/64 or an integer type),
  // and component_names holds the file's ComponentName attributes.
  std::map<std::string, VtuArray> point_data, cell_data;
  // Field data of the grid (<UnstructuredGrid><FieldData>), NumberOfTuples tuples each.
  std::map<std::string, VtuArray> field_data;
  // The grid's TimeValue field data (s), NaN when the file has none.
  double time = std::numeric_limits<double>::quiet_NaN();
};

VtuData read_vtu(const std::string& path);

// The steps of a PVD collection in file order: (timestep, file as written, i.e. relative to
// the directory of the .pvd file).
std::vector<std::pair<double, std::string>> read_pvd(const std::string& path);

}  // namespace cdem
