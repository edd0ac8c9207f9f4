#include "cdem/analysis/monitors.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "cdem/core/error.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {
namespace {

// Barycentric inside test with a relative tolerance, so points on a shared edge are found.
bool inside(const Model& m, std::int32_t b, Vec3 p) {
  const auto n0 = m.block_first_node[b];
  const ElemType t = m.block_type[b];
  const double tol = 1e-9;
  auto tri_in = [&](Vec3 a, Vec3 bb, Vec3 c) {
    const double area = cross(bb - a, c - a).z;
    const double l0 = cross(bb - p, c - p).z / area, l1 = cross(c - p, a - p).z / area;
    return l0 >= -tol && l1 >= -tol && 1 - l0 - l1 >= -tol;
  };
  switch (t) {
    case ElemType::Tri3: return tri_in(m.X(n0), m.X(n0 + 1), m.X(n0 + 2));
    case ElemType::Quad4:
      return tri_in(m.X(n0), m.X(n0 + 1), m.X(n0 + 2)) || tri_in(m.X(n0), m.X(n0 + 2), m.X(n0 + 3));
    case ElemType::Tet4: {
      const Vec3 a = m.X(n0), bb = m.X(n0 + 1), c = m.X(n0 + 2), d = m.X(n0 + 3);
      const double v = dot(bb - a, cross(c - a, d - a));
      const double l1 = dot(p - a, cross(c - a, d - a)) / v;
      const double l2 = dot(bb - a, cross(p - a, d - a)) / v;
      const double l3 = dot(bb - a, cross(c - a, p - a)) / v;
      return l1 >= -tol && l2 >= -tol && l3 >= -tol && 1 - l1 - l2 - l3 >= -tol;
    }
  }
  return false;
}

}  // namespace

std::int32_t find_block(const Model& m, Vec3 p) {
  for (std::size_t b = 0; b < m.n_blocks(); ++b)
    if (inside(m, static_cast<std::int32_t>(b), p)) return static_cast<std::int32_t>(b);
  return -1;
}

std::vector<std::int32_t> locate_monitors(const Model& m, const std::vector<Monitor>& monitors,
                                          const std::string& where) {
  std::vector<std::int32_t> out;
  for (std::size_t k = 0; k < monitors.size(); ++k) {
    const auto& mo = monitors[k];
    const auto b = find_block(m, mo.point);
    if (b < 0)
      throw InputError(fmt::format("{}: key 'monitor[{}].point': monitor '{}' at ({}, {}, {}) is "
                                   "outside the mesh",
                                   where, k, mo.name, mo.point.x, mo.point.y, mo.point.z));
    out.push_back(b);
  }
  return out;
}

MonitorSample sample_block(const Model& m, std::int32_t b) {
  MonitorSample s;
  s.stress = m.stress[b];
  s.von_mises = von_mises(s.stress);
  s.pressure = pressure(s.stress);
  const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
  for (auto n = n0; n < n1; ++n) {
    s.displacement += m.x[n] - m.X(n);
    s.velocity += m.v[n];
  }
  s.displacement = s.displacement / (n1 - n0);
  s.velocity = s.velocity / (n1 - n0);
  return s;
}

}  // namespace cdem
