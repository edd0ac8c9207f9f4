// Structured meshes built in code (tests, benchmarks): a box of cubes split into 6 positive
// tetrahedra, and the box face sets of any axis-aligned mesh.
#pragma once
#include <string>

#include "cdem/mesh/mesh.hpp"

namespace cdem {

// Face sets of an axis-aligned box mesh: every element face (edge) used by one element only,
// put in the set of the box side all its vertices lie on: "left"/"right" (x), "bottom"/"top"
// (y in 2D, z in 3D), "front"/"back" (y in 3D). Facets are in the order of their sorted
// vertex keys.
void add_box_face_sets(Mesh& mesh);

// nx x ny squares of side h from the origin (2D), each a quadrilateral (quads) or split into 2
// triangles along the (i, j)-(i+1, j+1) diagonal. One region "rock"; box face sets added.
Mesh structured_grid_2d(int nx, int ny, double h, bool quads);

// nx x ny x nz cubes of size/n from `origin`, each split into the 6 tetrahedra of the Kuhn
// triangulation (one per permutation of the axes; the same split in every cell keeps the mesh
// conforming); odd permutations get nodes 1 and 2 swapped so every tet is right-handed. One
// region; box face sets added.
Mesh structured_tet_box(int nx, int ny, int nz, Vec3 size, Vec3 origin = {},
                        const std::string& region = "rock");

}  // namespace cdem
