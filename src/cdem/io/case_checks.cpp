#include "cdem/io/case_checks.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "cdem/core/error.hpp"

namespace cdem {
namespace {

// Ratios beyond which sizes look like a unit mistake (a mesh in mm with a case in m is 1000x).
constexpr double kHoleToElement = 200;   // diameter / element size, either way
constexpr double kHoleToExtent = 5e-5;   // diameter / model extent, at least
constexpr double kLargestExtent = 2000;  // m: larger models are rare in rock blasting
constexpr double kSmallestExtent = 5e-3;
constexpr double kLargestElement = 50;  // m: a median element this large is a blast model in mm

}  // namespace

MeshScale mesh_scale(const Mesh& mesh) {
  MeshScale s;
  if (mesh.vertices.empty()) return s;
  Vec3 lo = mesh.vertices.front(), hi = lo;
  for (const Vec3& p : mesh.vertices)
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], p[i]);
      hi[i] = std::max(hi[i], p[i]);
    }
  s.extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  s.lo = lo;
  s.hi = hi;
  std::vector<double> sizes;
  sizes.reserve(mesh.num_elements());
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) {
    const int n = nodes_of(mesh.elem_type[e]);
    const auto& v = mesh.elem_vertices[e];
    double sum = 0;
    int edges = 0;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b) {
        // Quads: the four sides only (not the diagonals).
        if (mesh.elem_type[e] == ElemType::Quad4 && (b - a) == 2) continue;
        sum += norm(mesh.vertices[static_cast<std::size_t>(v[static_cast<std::size_t>(a)])] -
                    mesh.vertices[static_cast<std::size_t>(v[static_cast<std::size_t>(b)])]);
        ++edges;
      }
    sizes.push_back(sum / edges);
  }
  if (!sizes.empty()) {
    auto mid = sizes.begin() + static_cast<long>(sizes.size() / 2);
    std::nth_element(sizes.begin(), mid, sizes.end());
    s.element_size = *mid;
  }
  return s;
}

void check_case_against_mesh(const Case& c, const Mesh& mesh) {
  const std::string& f = c.path;
  if (mesh.dim == 2) {
    auto no_z = [&](const std::string& key, double z, const char* what) {
      if (z != 0)
        throw InputError(
            fmt::format("{}: key '{}': {} = {:g} in a 2D case (the mesh is 2D, in the "
                        "plane z = 0); a 2D run would drop it: give [x, y]",
                        f, key, what, z));
    };
    for (std::size_t i = 0; i < c.monitors.size(); ++i)
      no_z(fmt::format("monitor[{}].point", i), c.monitors[i].point.z, "z");
    for (std::size_t i = 0; i < c.holes.size(); ++i) {
      no_z(fmt::format("hole[{}].collar", i), c.holes[i].collar.z, "z");
      no_z(fmt::format("hole[{}].end", i), c.holes[i].end.z, "z (of the bottom)");
    }
    no_z("simulation.gravity", c.gravity.z, "the z component");
    for (std::size_t i = 0; i < c.boundaries.size(); ++i)
      if (c.boundaries[i].type == BoundaryType::Velocity)
        no_z(fmt::format("boundary[{}].velocity", i), c.boundaries[i].direction.z,
             "the z component");
    no_z("analysis.up", c.analysis.up.z, "the z component");
    if (c.initial_stress.enabled) {
      const char* comps[2] = {"yz", "xz"};
      for (const char* key : {"stress", "gradient"}) {
        const Sym6& s = key[0] == 's' ? c.initial_stress.at_reference : c.initial_stress.gradient;
        for (int k = 0; k < 2; ++k)
          if (s[4 + k] != 0)
            throw InputError(
                fmt::format("{}: key 'initial_stress.{}': the {} component {:g} in a "
                            "2D case (plane strain has no {} stress); a 2D run would "
                            "drop it: give 0 or [xx, yy, zz, xy]",
                            f, key, comps[k], s[4 + k], comps[k]));
      }
    }
  }

  // Holes in the model's neighbourhood: a collar or bottom more than one model size outside its
  // bounding box is no blasthole of this model (a typo or a unit mistake; far-away points
  // would also overflow the stations of the funnel analysis along the hole).
  const MeshScale s = mesh_scale(mesh);
  for (std::size_t i = 0; i < c.holes.size(); ++i) {
    const HoleDef& h = c.holes[i];
    if (!(h.diameter <= s.extent))
      throw InputError(
          fmt::format("{}: key 'hole[{}].diameter': hole '{}' is {:g} m wide, wider "
                      "than the model ({:g} m across)",
                      f, i, h.name, h.diameter, s.extent));
    for (const auto& [key, p] : {std::pair{"collar", h.collar}, std::pair{"end", h.end}}) {
      double out = 0;  // distance outside the bounding box
      for (int k = 0; k < mesh.dim; ++k) out = std::max({out, s.lo[k] - p[k], p[k] - s.hi[k]});
      if (!(out <= s.extent))
        throw InputError(
            fmt::format("{}: key 'hole[{}].{}': hole '{}' at ({:g}, {:g}, {:g}) is {:g} "
                        "m outside the model, which is {:g} m across",
                        f, i, key, h.name, p.x, p.y, p.z, out, s.extent));
    }
  }
  const std::string mesh_name =
      c.mesh_file.empty() ? "the generated mesh" : fmt::format("mesh file '{}'", c.mesh_file);
  if (s.extent > kLargestExtent || s.element_size > kLargestElement)
    spdlog::warn(
        "{}: the model is {:g} m across with a median element of {:g} m: is the mesh in "
        "millimetres? cdemblast works in metres",
        mesh_name, s.extent, s.element_size);
  if (s.extent > 0 && s.extent < kSmallestExtent)
    spdlog::warn(
        "{}: the model is only {:g} m across: is the mesh in kilometres? cdemblast "
        "works in metres",
        mesh_name, s.extent);
  for (std::size_t i = 0; i < c.holes.size(); ++i) {
    const HoleDef& h = c.holes[i];
    const double d = h.diameter;
    if (s.element_size > 0 &&
        (d * kHoleToElement < s.element_size || d > kHoleToElement * s.element_size))
      spdlog::warn(
          "{}: key 'hole[{}].diameter': hole '{}' is {:g} m across and the median "
          "element of {} is {:g} m ({:.3g} times the hole): are the mesh and the case "
          "in the same length unit (metres)?",
          f, i, h.name, d, mesh_name, s.element_size, s.element_size / d);
    else if (s.extent > 0 && (d < kHoleToExtent * s.extent || d > 0.5 * s.extent))
      spdlog::warn(
          "{}: key 'hole[{}].diameter': hole '{}' is {:g} m across in a model {:g} m "
          "across: are the mesh and the case in the same length unit (metres)?",
          f, i, h.name, d, s.extent);
  }
}

}  // namespace cdem
