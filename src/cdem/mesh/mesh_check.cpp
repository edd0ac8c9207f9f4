// Mesh checks shared by read_gmsh and generate_mesh: consistency, 2D plane and orientation,
// degenerate / inverted / non-convex elements. See check_mesh in gmsh_io.hpp.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/error.hpp"
#include "cdem/mesh/gmsh_io.hpp"

namespace cdem {
namespace {

// Relative tolerances of the checks (fractions of the mesh extent or of the mean measure).
constexpr double plane_tol = 1e-12;       // |z| of a 2D mesh, relative to its extent
constexpr double degenerate_tol = 1e-12;  // |area| or |volume|, relative to the mean
constexpr double outlier_ratio = 1e9;     // |area| or |volume| against the median's: refused
constexpr double outlier_warn = 1e6;      // the same: warned (graded meshes stay far below)

class Checker {
 public:
  Checker(Mesh& mesh, const std::string& source) : m_(mesh), source_(source) {}

  void run() {
    check_structure();
    check_finite();
    if (m_.dim == 2)
      check_2d();
    else
      check_3d();
  }

 private:
  Mesh& m_;
  const std::string& source_;

  std::string elem_name(std::size_t e) const {
    const std::string type = name_of(m_.elem_type[e]);
    if (e < m_.elem_tag.size()) return fmt::format("element {} ({})", m_.elem_tag[e], type);
    return fmt::format("element #{} ({})", e, type);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw MeshError(fmt::format("{}: {}", source_, what));
  }
  [[noreturn]] void fail_elem(std::size_t e, const std::string& what) const {
    fail(fmt::format("{}: {}", elem_name(e), what));
  }

  void check_structure() {
    if (m_.dim != 2 && m_.dim != 3)
      fail(fmt::format("mesh dimension {} (expected 2 or 3)", m_.dim));
    const std::size_t ne = m_.elem_type.size();
    if (ne == 0) fail(fmt::format("no {}D elements", m_.dim));
    if (m_.elem_vertices.size() != ne || m_.elem_region.size() != ne ||
        (!m_.elem_tag.empty() && m_.elem_tag.size() != ne))
      fail("inconsistent element arrays (type, vertices, region and tag counts differ)");
    const auto nv = static_cast<std::int64_t>(m_.vertices.size());
    const auto nr = static_cast<std::int32_t>(m_.region_names.size());
    for (std::size_t e = 0; e < ne; ++e) {
      const ElemType t = m_.elem_type[e];
      const bool ok_type =
          m_.dim == 2 ? (t == ElemType::Tri3 || t == ElemType::Quad4) : t == ElemType::Tet4;
      if (!ok_type) fail_elem(e, fmt::format("not a {}D element type", m_.dim));
      const int n = nodes_of(t);
      for (int k = 0; k < 4; ++k) {
        const std::int32_t v = m_.elem_vertices[e][static_cast<std::size_t>(k)];
        if (k < n && (v < 0 || v >= nv))
          fail_elem(e, fmt::format("vertex index {} out of range", v));
        if (k >= n && v != -1) fail_elem(e, "unused vertex slot is not -1");
      }
      if (m_.elem_region[e] < 0 || m_.elem_region[e] >= nr)
        fail_elem(e, fmt::format("region index {} out of range", m_.elem_region[e]));
    }
    const int fn = m_.dim;  // vertices per facet: 2 (edge) or 3 (triangle)
    for (const FaceSet& fs : m_.face_sets) {
      for (std::size_t f = 0; f < fs.facets.size(); ++f) {
        const Facet& fc = fs.facets[f];
        if (fc.count() != fn)
          fail(fmt::format("face set '{}': facet {} has {} vertices (expected {})", fs.name, f,
                           fc.count(), fn));
        for (int k = 0; k < fn; ++k) {
          const std::int32_t v = fc.v[static_cast<std::size_t>(k)];
          if (v < 0 || v >= nv)
            fail(
                fmt::format("face set '{}': facet {} vertex index {} out of range", fs.name, f, v));
        }
      }
    }
  }

  void check_finite() const {
    for (std::size_t i = 0; i < m_.vertices.size(); ++i) {
      const Vec3& p = m_.vertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        fail(fmt::format("vertex {} at ({}, {}, {}) is not finite", i, p.x, p.y, p.z));
    }
  }

  // An element far larger than the median one: a misplaced vertex (a corrupt coordinate, a
  // node in other units). Reported before the degenerate test, which compares with the mean.
  void check_outlier(const std::vector<double>& measure, const char* what, int power) const {
    std::vector<double> sorted(measure);
    const auto mid = sorted.begin() + static_cast<long>((sorted.size() - 1) / 2);
    std::nth_element(sorted.begin(), mid, sorted.end());
    const double median = *mid;
    const auto big = static_cast<std::size_t>(std::max_element(measure.begin(), measure.end()) -
                                              measure.begin());
    if (median > 0 && measure[big] > outlier_warn * median) {
      std::string corners;
      for (int k = 0; k < nodes_of(m_.elem_type[big]); ++k) {
        const Vec3 p = x(big, k);
        corners += fmt::format("{}({:g}, {:g}, {:g})", k ? ", " : "", p.x, p.y, p.z);
      }
      const std::string what_is =
          fmt::format("{} {:g} m^{} is {:.3g} times the median element's ({:g} m^{}): a "
                      "misplaced vertex? Its vertices: {}",
                      what, measure[big], power, measure[big] / median, median, power, corners);
      if (measure[big] > outlier_ratio * median) fail_elem(big, what_is);
      spdlog::warn("{}: {}: {}", source_, elem_name(big), what_is);
    }
  }

  Vec3 x(std::size_t e, int k) const {
    return m_.vertices[static_cast<std::size_t>(m_.elem_vertices[e][static_cast<std::size_t>(k)])];
  }

  // Twice the signed area of a 2D element (z component of the cross products; the shoelace
  // formula for the quadrilateral: (x2 - x0) x (x3 - x1)).
  double twice_area(std::size_t e) const {
    if (m_.elem_type[e] == ElemType::Tri3) return cross(x(e, 1) - x(e, 0), x(e, 2) - x(e, 0)).z;
    return cross(x(e, 2) - x(e, 0), x(e, 3) - x(e, 1)).z;
  }

  void check_2d() {
    // The plane: plane strain lives in z = 0.
    Vec3 lo = m_.vertices.front(), hi = lo;
    for (const Vec3& p : m_.vertices)
      for (int i = 0; i < 3; ++i) {
        lo[i] = std::min(lo[i], p[i]);
        hi[i] = std::max(hi[i], p[i]);
      }
    const double extent = norm(hi - lo);
    for (std::size_t i = 0; i < m_.vertices.size(); ++i) {
      if (std::abs(m_.vertices[i].z) > plane_tol * extent) {
        // Name an element using the vertex, for the user to find it.
        for (std::size_t e = 0; e < m_.num_elements(); ++e)
          for (int k = 0; k < nodes_of(m_.elem_type[e]); ++k)
            if (m_.elem_vertices[e][static_cast<std::size_t>(k)] == static_cast<std::int32_t>(i))
              fail_elem(e, fmt::format("vertex at z = {:g} off the z = 0 plane of a 2D mesh "
                                       "(plane strain meshes must lie in z = 0)",
                                       m_.vertices[i].z));
        fail(fmt::format("vertex {} at z = {:g} off the z = 0 plane of a 2D mesh", i,
                         m_.vertices[i].z));
      }
    }
    for (Vec3& p : m_.vertices) p.z = 0.0;

    const std::size_t ne = m_.num_elements();
    std::vector<double> area(ne);
    for (std::size_t e = 0; e < ne; ++e) area[e] = 0.5 * std::abs(twice_area(e));
    check_outlier(area, "area", 2);
    double mean = 0;
    for (std::size_t e = 0; e < ne; ++e) mean += std::abs(twice_area(e));
    mean /= static_cast<double>(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      const double a2 = twice_area(e);
      if (!(std::abs(a2) >= degenerate_tol * mean))
        fail_elem(e, fmt::format("degenerate element (area {:g} m^2, mean {:g} m^2)", 0.5 * a2,
                                 0.5 * mean));
      auto& v = m_.elem_vertices[e];
      if (a2 < 0) {  // clockwise: reverse the cycle, keeping vertex 0
        if (m_.elem_type[e] == ElemType::Tri3)
          std::swap(v[1], v[2]);
        else
          std::swap(v[1], v[3]);
      }
      if (m_.elem_type[e] == ElemType::Quad4) {
        // Corner k: (x[k+1] - x[k]) x (x[k-1] - x[k]) > 0 for a convex counter-clockwise quad.
        for (int k = 0; k < 4; ++k) {
          const Vec3 c = x(e, k);
          const double z = cross(x(e, (k + 1) % 4) - c, x(e, (k + 3) % 4) - c).z;
          if (!(z > degenerate_tol * std::abs(a2)))
            fail_elem(e,
                      fmt::format("non-convex or self-intersecting quadrilateral (corner {})", k));
        }
      }
    }
  }

  void check_3d() {
    const std::size_t ne = m_.num_elements();
    auto six_volume = [&](std::size_t e) {
      const Vec3 x0 = x(e, 0);
      return dot(x(e, 1) - x0, cross(x(e, 2) - x0, x(e, 3) - x0));
    };
    std::vector<double> volume(ne);
    for (std::size_t e = 0; e < ne; ++e) volume[e] = std::abs(six_volume(e)) / 6;
    check_outlier(volume, "volume", 3);
    double mean = 0;
    for (std::size_t e = 0; e < ne; ++e) mean += std::abs(six_volume(e));
    mean /= static_cast<double>(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      const double v6 = six_volume(e);
      if (!(std::abs(v6) >= degenerate_tol * mean))
        fail_elem(e, fmt::format("degenerate element (volume {:g} m^3, mean {:g} m^3)", v6 / 6,
                                 mean / 6));
      if (v6 < 0)
        fail_elem(e, fmt::format("inverted tetrahedron (negative volume): V = {:g} m^3", v6 / 6));
    }
  }
};

}  // namespace

void check_mesh(Mesh& mesh, const std::string& source) { Checker(mesh, source).run(); }

}  // namespace cdem
