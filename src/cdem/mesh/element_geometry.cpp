#include "cdem/mesh/element_geometry.hpp"

#include <algorithm>
#include <cmath>

namespace cdem {

double signed_measure(ElemType t, std::span<const Vec3> p) {
  switch (t) {
    case ElemType::Tri3: return 0.5 * cross(p[1] - p[0], p[2] - p[0]).z;
    case ElemType::Quad4:
      return 0.5 * ((p[0].x * p[1].y - p[1].x * p[0].y) + (p[1].x * p[2].y - p[2].x * p[1].y) +
                    (p[2].x * p[3].y - p[3].x * p[2].y) + (p[3].x * p[0].y - p[0].x * p[3].y));
    case ElemType::Tet4: return dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0])) / 6.0;
  }
  return 0.0;
}

namespace {
double tri_altitude(Vec3 a, Vec3 b, Vec3 c) {
  const double area2 = norm(cross(b - a, c - a));
  const double lmax = std::max({norm(b - a), norm(c - b), norm(a - c)});
  return lmax > 0 ? area2 / lmax : 0.0;
}
}  // namespace

double smallest_altitude(ElemType t, std::span<const Vec3> p) {
  switch (t) {
    case ElemType::Tri3: return tri_altitude(p[0], p[1], p[2]);
    case ElemType::Quad4: {
      // The smallest altitude of the four corner triangles bounds the quad's thinnest width.
      double h = tri_altitude(p[3], p[0], p[1]);
      for (int i = 1; i < 4; ++i) h = std::min(h, tri_altitude(p[i - 1], p[i], p[(i + 1) % 4]));
      return h;
    }
    case ElemType::Tet4: {
      const double v6 = std::abs(dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0])));
      double amax = 0;
      const LocalFaces lf = local_faces(t);
      for (int k = 0; k < 4; ++k) {
        const auto& q = lf.f[k];
        amax = std::max(amax, 0.5 * norm(cross(p[q[1]] - p[q[0]], p[q[2]] - p[q[0]])));
      }
      return amax > 0 ? (v6 / 2.0) / amax : 0.0;  // h = 3V / A_max
    }
  }
  return 0.0;
}

double characteristic_size(ElemType t, double measure) {
  switch (t) {
    case ElemType::Tri3: return std::sqrt(2.0 * measure);
    case ElemType::Quad4: return std::sqrt(measure);
    case ElemType::Tet4: return std::cbrt(6.0 * measure);
  }
  return 0.0;
}

}  // namespace cdem
