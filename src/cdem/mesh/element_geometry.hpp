// Geometry of the block element types: local faces with outward orientation, measures,
// smallest altitude and characteristic size.
#pragma once
#include <array>
#include <span>

#include "cdem/core/vec3.hpp"
#include "cdem/mesh/mesh.hpp"

namespace cdem {

// Local faces (3D) or edges (2D), ordered so that the right-hand rule (3D: cross(p1-p0, p2-p0);
// 2D: (t.y, -t.x) with t = p1 - p0, for counter-clockwise elements) gives the outward normal.
struct LocalFaces {
  int count;
  int nodes_per_face;
  std::array<std::array<int, 3>, 4> f;
};
constexpr LocalFaces local_faces(ElemType t) {
  switch (t) {
    case ElemType::Tri3: return {3, 2, {{{0, 1, -1}, {1, 2, -1}, {2, 0, -1}, {-1, -1, -1}}}};
    case ElemType::Quad4: return {4, 2, {{{0, 1, -1}, {1, 2, -1}, {2, 3, -1}, {3, 0, -1}}}};
    case ElemType::Tet4: return {4, 3, {{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}}};
  }
  return {0, 0, {}};
}

// Outward area vector of a face/edge: |n| = area (2D: length x 1 m).
inline Vec3 face_area_vector(std::span<const Vec3> p, int nodes_per_face) {
  if (nodes_per_face == 2) {
    const Vec3 t = p[1] - p[0];
    return {t.y, -t.x, 0.0};
  }
  return 0.5 * cross(p[1] - p[0], p[2] - p[0]);
}

// Signed measure: area (2D, positive counter-clockwise; quad by the shoelace formula) or
// volume (tet, positive for the right-handed order).
double signed_measure(ElemType t, std::span<const Vec3> p);

// Smallest altitude h_e (used for the stable time step h_e / c_p, SPEC 1.1).
double smallest_altitude(ElemType t, std::span<const Vec3> p);

// Characteristic size L_c of a block: the edge of the square or cube cell it comes from
// (triangle sqrt(2A), quad sqrt(A), tet (6V)^(1/3)): a structured mesh of cells of size h
// gives L_c = h for every block type. Used for the spring stiffness k_n = alpha E / h and the
// bar model's attenuation (r0 / L_c)^a.
double characteristic_size(ElemType t, double measure);

}  // namespace cdem
