// The largest eigenvalue of a small dense symmetric matrix (set-up only: element eigenvalues
// for the stable time step). Cyclic Jacobi rotations (Golub & Van Loan, Matrix Computations,
// 4th ed., sec. 8.5): converges quadratically; swept until the off-diagonal norm is below
// 1e-14 of the matrix norm.
#pragma once
#include <algorithm>
#include <cmath>

namespace cdem {

// a: n x n row-major, symmetric, n <= N; destroyed.
template <int N>
double sym_max_eigenvalue(double (&a)[N][N], int n) {
  double total = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) total += a[i][j] * a[i][j];
  if (total == 0) return 0;
  for (int sweep = 0; sweep < 60; ++sweep) {
    double off = 0;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) off += a[i][j] * a[i][j];
    if (off <= 1e-28 * total) break;
    for (int p = 0; p < n; ++p)
      for (int q = p + 1; q < n; ++q) {
        if (a[p][q] == 0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) {  // columns p, q
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) {  // rows p, q
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
      }
  }
  double mx = a[0][0];
  for (int i = 1; i < n; ++i) mx = std::max(mx, a[i][i]);
  return mx;
}

}  // namespace cdem
