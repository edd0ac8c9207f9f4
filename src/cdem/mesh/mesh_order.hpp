// The mesh's elements and vertices put in the order of a Hilbert curve through the model.
//
// A CDEM step is a sequence of gathers: a spring point reads the nodes of two neighbouring
// blocks, a vertex cluster the nodes of every block around its vertex, a contact pair a node and
// a nearby block, the gas an opened interface and its two blocks. Each such read is a cache miss
// unless the blocks that are near in space are near in memory. Gmsh numbers the elements of a
// generated 3D mesh in no spatial order (the coarse SPEC 5.3 cylinder: consecutive tetrahedra
// lie 1 m apart in a model of 0.1 m blocks; the median index distance to the 4 nearest blocks
// was 658), so set-up reorders the mesh once, before the CDEM split: elements by the Hilbert
// key of their centroid, vertices by that of their position (ties by the file's order, so the
// order is a function of the mesh alone: the same for every run, restart and thread count).
// The element's number in the file (elem_tag) goes with it, for messages.
#pragma once

#include <cstdint>

#include "cdem/mesh/mesh.hpp"

namespace cdem {

// The 63-bit Hilbert key of grid point (x, y, z), each coordinate in [0, 2^21) (Skilling,
// "Programming the Hilbert curve", AIP Conf. Proc. 707, 381 (2004): axes to transpose, then the
// transpose's bits interleaved from the most significant).
std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z);

// Reorders the mesh's elements and vertices along the Hilbert curve through its bounding box
// (elem_* arrays, vertices, and the face sets' facets renumbered to the new vertex numbers).
void order_mesh_spatially(Mesh& mesh);

}  // namespace cdem
