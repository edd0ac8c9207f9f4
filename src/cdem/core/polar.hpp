// Polar decomposition F = R U of a 3x3 or 2x2 deformation gradient (R a rotation, U symmetric
// positive definite). Used by the co-rotational block kernels (SPEC 1.2).
#pragma once
#include <cmath>

#include "cdem/core/vec3.hpp"

namespace cdem {

// 2D (in-plane): R = [[c, -s], [s, c]] with (c, s) = normalize(F00 + F11, F10 - F01), which
// maximises tr(R^T F) and so is the rotation of the polar decomposition (exact, no iteration).
inline void polar_2d(double f00, double f01, double f10, double f11, double& c, double& s) {
  const double a = f00 + f11, b = f10 - f01;
  const double r = std::sqrt(a * a + b * b);
  if (r > 0) {
    c = a / r;
    s = b / r;
  } else {
    c = 1.0;
    s = 0.0;
  }
}

// 3D: Newton iteration R <- (R + R^-T) / 2 from R = F (Higham 1986, "Computing the polar
// decomposition with applications", SIAM J. Sci. Stat. Comput. 7). Quadratic convergence:
// a strain of 1e-3 needs 3-4 iterations to reach round-off. Returns the number of iterations;
// det(F) <= 0 (an inverted element) returns -1 and R = identity.
// The Newton iteration itself, from the R given (det R > 0): stops when no entry changes by
// `tol` or more, at most 30 iterations; returns the number done.
inline int polar_newton(Mat3& R, double tol) {
  for (int it = 1; it <= 30; ++it) {
    const Mat3 it_t = transpose(inverse(R));
    double diff = 0;
    for (int k = 0; k < 9; ++k) {
      const double nv = 0.5 * (R.m[k] + it_t.m[k]);
      diff = std::max(diff, std::abs(nv - R.m[k]));
      R.m[k] = nv;
    }
    if (diff < tol) return it;
  }
  return 30;
}

inline int polar_3d(const Mat3& F, Mat3& R) {
  if (!(det(F) > 0)) {
    R = Mat3::identity();
    return -1;
  }
  R = F;
  return polar_newton(R, 1e-15);
}

}  // namespace cdem
