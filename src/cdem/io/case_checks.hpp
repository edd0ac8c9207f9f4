// Plausibility checks of a case against its mesh, before the model is built (docs/input_safety.md):
//   errors (InputError naming the key): 3D values in a 2D case (a z coordinate of a point, a
//     z component of gravity, a velocity or `up`, yz/xz components of the in-situ stress), which
//     a 2D run would silently drop; a hole's collar or bottom more than the model's size
//     outside its bounding box;
//   warnings (spdlog, naming the sizes): model extent, median element size and hole diameters
//     whose ratios suggest that the mesh and the case are in different length units.
#pragma once
#include "cdem/io/case.hpp"
#include "cdem/mesh/mesh.hpp"

namespace cdem {

void check_case_against_mesh(const Case& c, const Mesh& mesh);

// The sizes the unit check compares: the mesh's largest bounding-box side and the median of the
// elements' mean edge lengths (m).
struct MeshScale {
  double extent = 0;
  double element_size = 0;
  Vec3 lo, hi;  // bounding box
};
MeshScale mesh_scale(const Mesh& mesh);

}  // namespace cdem
