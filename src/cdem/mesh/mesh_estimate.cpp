#include "cdem/mesh/mesh_estimate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cdem/core/error.hpp"
#include "cdem/core/resources.hpp"

namespace cdem {
namespace {

constexpr double kPerCell2D = 2.3;  // triangles per h^2
constexpr double kPerCell3D = 6.0;  // tetrahedra per h^3

// Elements within distance r of a point or of a segment of length len (a ball or disc plus a
// tube or strip) at size s, plus those of the shell r..outer over which the size grows linearly
// from s to h (midpoint rule over 64 shells).
double refined_zone(int dim, double r, double outer, double len, double s, double h) {
  const double pi = std::numbers::pi;
  const double per = dim == 2 ? kPerCell2D : kPerCell3D;
  auto measure = [&](double rho) {  // of the zone within rho
    return dim == 2 ? pi * rho * rho + 2 * rho * len
                    : 4.0 / 3.0 * pi * rho * rho * rho + pi * rho * rho * len;
  };
  auto boundary = [&](double rho) {  // d measure / d rho
    return dim == 2 ? 2 * pi * rho + 2 * len : 4 * pi * rho * rho + 2 * pi * rho * len;
  };
  double n = measure(r) / std::pow(s, dim);
  constexpr int steps = 64;
  const double width = outer - r;
  for (int i = 0; i < steps; ++i) {
    const double f = (i + 0.5) / steps;
    const double size = s + (h - s) * f;
    n += boundary(r + width * f) * (width / steps) / std::pow(size, dim);
  }
  return per * n;
}

}  // namespace

MeshEstimate estimate_generated_mesh(const GenerateSpec& s) {
  const double pi = std::numbers::pi;
  MeshEstimate est;
  const int dim = s.shape == "rectangle" ? 2 : 3;
  const double per = dim == 2 ? kPerCell2D : kPerCell3D;
  const double h = s.element_size;
  double measure = 0, extent = 0;
  if (s.shape == "rectangle") {
    measure = s.size.x * s.size.y;
    extent = std::max(s.size.x, s.size.y);
  } else if (s.shape == "box") {
    measure = s.size.x * s.size.y * s.size.z;
    extent = std::max({s.size.x, s.size.y, s.size.z});
  } else {
    measure = pi * s.size.x * s.size.x * s.size.z;
    extent = std::max(2 * s.size.x, s.size.z);
  }
  double best = 0;
  // Adds the elements of one part of the spec; remembers the largest part (NaN or infinity too).
  auto part = [&](double n, const std::string& what, const std::string& key) {
    n = std::max(0.0, n);
    est.elements += n;
    if (!(n <= best) || est.largest.empty()) best = n, est.largest = what, est.largest_key = key;
  };
  // The body; the ring of a cylinder at its own size.
  if (s.ring_width > 0 && s.shape == "cylinder") {
    const double rin = std::max(0.0, s.size.x - s.ring_width);
    const double ring = pi * (s.size.x * s.size.x - rin * rin) * s.size.z;
    const double hr = s.ring_element_size > 0 ? s.ring_element_size : h;
    part(per * (measure - ring) / std::pow(h, dim), fmt::format("element_size {:g} m", h),
         "element_size");
    part(per * ring / std::pow(hr, dim), fmt::format("ring_element_size {:g} m", hr),
         "ring_element_size");
  } else {
    part(per * measure / std::pow(h, dim), fmt::format("element_size {:g} m", h), "element_size");
  }
  for (std::size_t i = 0; i < s.refine.size(); ++i) {
    const RefineSpec& r = s.refine[i];
    if (r.size < h)
      part(refined_zone(dim, r.radius, refine_outer(r, h), r.to ? norm(*r.to - r.point) : 0.0,
                        r.size, h),
           fmt::format("refine[{}]: size {:g} m within {:g} m{}", i, r.size, r.radius,
                       r.to ? " of a segment" : ""),
           fmt::format("refine[{}].size", i));
  }
  // Curved walls sized from curvature: a wall of radius r gets elements of 2 pi r / n; count a
  // layer of three such elements around it (over the hole's length in 3D) and the grading back
  // to element_size.
  if (s.circle_segments > 0) {
    const double n = s.circle_segments;
    auto wall = [&](double radius, double length, const std::string& what, const std::string& key) {
      const double a = std::min(h, 2 * pi * radius / n);
      if (!(a < h)) return;
      const double layer = 3 * a;
      const double shell = dim == 2 ? 2 * pi * (radius + layer / 2) * layer
                                    : 2 * pi * (radius + layer / 2) * layer * length;
      part(per * shell / std::pow(a, dim) + refined_zone(dim, radius + layer, 2 * (radius + layer), 0.0, a, h) / 4,
           fmt::format("{} (walls sized by circle_segments = {} give elements of {:g} m)", what,
                       s.circle_segments, a),
           key);
    };
    for (std::size_t i = 0; i < s.holes.size(); ++i) {
      const HoleSpec& hole = s.holes[i];
      wall(hole.radius, hole.depth > 0 ? hole.depth : 2 * extent,
           fmt::format("hole[{}] of radius {:g} m", i, hole.radius),
           fmt::format("hole[{}].radius", i));
    }
    if (s.shape == "cylinder") wall(s.size.x, s.size.z, "the cylinder's wall", "circle_segments");
  }
  est.bytes = est.elements * (dim == 2 ? kBytesPerElement2D : kBytesPerElement3D);
  return est;
}

std::string model_size_problem(double elements, int dim, const std::string& culprit) {
  const double bytes = elements * (dim == 2 ? kBytesPerElement2D : kBytesPerElement3D);
  const std::string because = culprit.empty() ? "" : fmt::format(" ({})", culprit);
  if (!(elements <= kMaxElements))
    return fmt::format(
        "about {:.3g} elements{}, more than the {:.0e} cdemblast takes (about {} "
        "of memory); use larger element sizes",
        elements, because, kMaxElements, format_bytes(bytes));
  const AvailableMemory mem = available_memory();
  if (mem.bytes > 0 && bytes > 0.8 * static_cast<double>(mem.bytes))
    return fmt::format(
        "about {:.3g} elements{} need about {} of memory; this machine has {} "
        "available ({}); use larger element sizes",
        elements, because, format_bytes(bytes), format_bytes(static_cast<double>(mem.bytes)),
        mem.source);
  return "";
}

void check_model_size(double elements, int dim, const std::string& what,
                      const std::string& culprit) {
  const std::string why = model_size_problem(elements, dim, culprit);
  if (!why.empty()) throw MeshError(fmt::format("{}: {}", what, why));
}

}  // namespace cdem
