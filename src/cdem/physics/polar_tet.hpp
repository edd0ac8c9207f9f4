// Polar rotation of the tet kernel: the Newton iteration of cdem::polar_3d (core/polar.hpp, the
// reference) with a stopping test that does not pay an iteration to confirm convergence.
//
// Newton R <- (R + R^-T) / 2 from R = F = Q U (Q the rotation sought, U = V diag(s) V^T)
// acts on the singular values only: R_k = Q V diag(s_k) V^T with s_{k+1} = (s_k + 1 / s_k) / 2,
// so e_k = s_k - 1 obeys e_{k+1} = e_k^2 / (2 (1 + e_k)) (quadratic; e_k >= 0 from k = 1 on).
// The change of iteration k is d_k = max_ij |R_{k+1} - R_k|_ij, and
// |R_{k+1} - R_k|_2 = max |e_k - e_{k+1}| <= 3 d_k (the 2-norm of a 3x3 matrix is at most 3
// times its largest entry). Since |e_k - e_{k+1}| >= |e_k| / 2 for any e_k > -1, |e_k| <= 6 d_k
// and the error left in R_{k+1} is |R_{k+1} - Q|_2 = max e_{k+1} <= e_k^2 / (2 (1 + e_k)),
// about 18 d_k^2 at small strain.
// Stopping when d_k < 1e-9 leaves at most ~2e-17, below the round-off of R (1.1e-16 per
// entry): the iteration the reference adds to see a change below 1e-15 changes R only by
// rounding. A strain of 5e-4 takes 3 iterations instead of 4, a strain of 1e-6 2 instead of 3,
// a strain below ~5e-10 1 instead of 2.
//
// block_forces_tet (physics/block_forces.cpp) runs this same iteration vectorised across blocks,
// written out with explicit FMAs that reproduce this function's rounding as GCC 12 compiles it:
// a change here must be made there too (the kernel's results are bitwise those of this scalar
// path, which mean_polar_iterations in solver/bench.cpp still uses).
#pragma once
#include <algorithm>
#include <cmath>

#include "cdem/core/polar.hpp"
#include "cdem/core/vec3.hpp"

namespace cdem {

// Returns the number of iterations (0: F was already orthogonal to round-off); det(F) <= 0 (an inverted element) returns -1 and
// R = identity, as polar_3d.
inline int polar_3d_tet(const Mat3& F, Mat3& R) {
  if (!(det(F) > 0)) {
    R = Mat3::identity();
    return -1;
  }
  R = F;
  // F orthogonal to round-off (a block at rest, or rigidly rotated): R = F. With U = I + E,
  // F^T F - I = U^2 - I = 2 E + E^2, so entries below 1e-15 bound |E|_2 by ~1.5e-15 (a few
  // ulp; typically ~1e-16 for a block at rest, whose F = Dm Dm^-1 is I to the rounding of
  // Dm^-1), the size of the rounding a Newton iteration itself leaves. det F > 0 (above)
  // excludes the reflections, also orthogonal. 18 multiply-adds instead of a Newton
  // iteration (an inverse with a division) for the blocks a wave has not reached yet.
  {
    auto col_dot = [&F](int i, int j) {
      return F(0, i) * F(0, j) + F(1, i) * F(1, j) + F(2, i) * F(2, j);
    };
    const double dev = std::max({std::abs(col_dot(0, 0) - 1.0), std::abs(col_dot(1, 1) - 1.0),
                                 std::abs(col_dot(2, 2) - 1.0), std::abs(col_dot(0, 1)),
                                 std::abs(col_dot(1, 2)), std::abs(col_dot(0, 2))});
    if (dev < 1e-15) return 0;
  }
  return polar_newton(R, 1e-9);  // error left <= ~18 diff^2 (above)
}

}  // namespace cdem
