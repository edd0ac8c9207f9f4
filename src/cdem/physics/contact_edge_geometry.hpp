// The edge contacts' geometry and tests (contact_edge_geometry.cpp), shared by the passes over
// the block pairs (contact_edges.cpp). Internal to the contact kernel; the functions the tests
// compare are declared in contact.hpp.
#pragma once
#include <array>
#include <cstdint>

#include "cdem/model/model.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {

// The six edges of a tetrahedron and, per edge, its two faces (the faces opposite the other two
// nodes: face k of local_faces(Tet4) is opposite node k).
inline constexpr std::array<std::array<int, 2>, 6> kTetEdges = {{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
inline constexpr std::array<std::array<int, 2>, 6> kTetEdgeFaces = {{{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}}};

inline std::int32_t edge_key(int ea, int eb) { return 6 * ea + eb; }
// ContactSet::bp_hits: bits 0-35 the edge pairs found touching (edge_key), then the block pair's
// edges of a and of b that may reach into the other (6 bits each) and whether the pair is near
inline constexpr int kHitsMaskA = 36, kHitsMaskB = 42, kHitsNear = 48;

// Block b's geometry this step (the node pairs' face planes when it is one of their blocks).
void tet_geom(const Model& m, const ContactSet& cs, std::int32_t b, TetGeom& g);
// The block's centroid and bounding radius (the first, cheap test of a block pair).
// Is every node of S in front of one face plane of G (beyond tol)? Else `edges`: the edges of S
// that may have a point inside G; when separated, `gap`: how far (contact_edge_geometry.cpp).
bool separated(const TetGeom& G, const TetGeom& S, int& edges, double& gap);

}  // namespace cdem
