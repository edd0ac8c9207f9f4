// The tet kernel's polar rotation (physics/polar_tet.hpp) against the reference Newton iteration
// (core/polar.hpp) on random deformation gradients F = Q (I + E) (Q a random rotation, E a
// random symmetric strain of a given size) and on general random matrices.
//
// Tolerances: both iterations compute the same iterates; the reference only runs one more,
// which changes R by rounding: each entry of R^-T carries a few ulp (cofactor differences of
// products, one division), so the extra iteration moves an entry by at most ~4 ulp of 1
// (4.4e-16); 2e-15 (~10 ulp) is that with a margin, and 1e-13 relative to the largest
// singular value for the general matrices (their conditioning amplifies the same rounding).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "cdem/core/polar.hpp"
#include "cdem/physics/polar_tet.hpp"

namespace cdem {
namespace {

Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  // Unit quaternion from 4 normals.
  double q[4];
  double s = 0;
  for (double& c : q) {
    c = nd(rng);
    s += c * c;
  }
  s = std::sqrt(s);
  const double w = q[0] / s, x = q[1] / s, y = q[2] / s, z = q[3] / s;
  Mat3 r;
  r(0, 0) = 1 - 2 * (y * y + z * z); r(0, 1) = 2 * (x * y - w * z); r(0, 2) = 2 * (x * z + w * y);
  r(1, 0) = 2 * (x * y + w * z); r(1, 1) = 1 - 2 * (x * x + z * z); r(1, 2) = 2 * (y * z - w * x);
  r(2, 0) = 2 * (x * z - w * y); r(2, 1) = 2 * (y * z + w * x); r(2, 2) = 1 - 2 * (x * x + y * y);
  return r;
}

double max_abs_diff(const Mat3& a, const Mat3& b) {
  double d = 0;
  for (int k = 0; k < 9; ++k) d = std::max(d, std::abs(a.m[k] - b.m[k]));
  return d;
}

TEST(PolarTet, MatchesReferenceOnStrainedRotations) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> ud(-1.0, 1.0);
  for (double strain : {0.0, 1e-14, 1e-12, 1e-10, 1e-8, 1e-6, 5e-4, 5e-3, 5e-2, 0.3}) {
    int saved = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      const Mat3 Q = random_rotation(rng);
      Mat3 U = Mat3::identity();  // I + E, E symmetric
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
          const double e = strain * ud(rng);
          U(i, j) += e;
          if (j != i) U(j, i) += e;
        }
      const Mat3 F = Q * U;
      Mat3 r_ref, r_new;
      const int it_ref = polar_3d(F, r_ref);
      const int it_new = polar_3d_tet(F, r_new);
      ASSERT_GT(it_ref, 0);
      ASSERT_GE(it_new, 0);
      EXPECT_LE(it_new, it_ref) << "strain " << strain;
      saved += it_ref - it_new;
      EXPECT_LE(max_abs_diff(r_new, r_ref), 2e-15) << "strain " << strain << " trial " << trial;
      // Q itself (the exact rotation of F), to the round-off of Q's construction.
      EXPECT_LE(max_abs_diff(r_new, Q), 2e-15) << "strain " << strain << " trial " << trial;
      // Orthogonal.
      EXPECT_LE(max_abs_diff(transpose(r_new) * r_new, Mat3::identity()), 2e-15);
    }
    // The confirming iteration is saved in most trials, except near a strain of 1e-8 (the
    // reference's second change, ~strain^2 / 2, is then already below its 1e-15) and in the few
    // trials whose last change happens to fall below 1e-15 before the confirmation.
    if (strain >= 1e-12 && strain <= 5e-3 && strain != 1e-8) {
      EXPECT_GE(saved, 1900) << "strain " << strain;
    }
  }
}

TEST(PolarTet, MatchesReferenceOnGeneralMatrices) {
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> ud(-1.0, 1.0);
  int tested = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    Mat3 F;
    for (double& c : F.m) c = ud(rng);
    if (!(det(F) > 1e-3)) continue;  // inverted or nearly singular: see the next test
    Mat3 r_ref, r_new;
    const int it_ref = polar_3d(F, r_ref);
    const int it_new = polar_3d_tet(F, r_new);
    ASSERT_GE(it_new, 0);
    EXPECT_LE(it_new, it_ref);
    EXPECT_LE(max_abs_diff(r_new, r_ref), 1e-13) << "trial " << trial;
    EXPECT_LE(max_abs_diff(transpose(r_new) * r_new, Mat3::identity()), 1e-13);
    // R^T F symmetric (U of the polar split).
    const Mat3 U = transpose(r_new) * F;
    EXPECT_LE(max_abs_diff(U, transpose(U)), 1e-13);
    ++tested;
  }
  EXPECT_GT(tested, 1000);
}

TEST(PolarTet, InvertedReturnsIdentity) {
  Mat3 F = Mat3::identity();
  F(2, 2) = -1e-3;
  Mat3 R;
  EXPECT_EQ(polar_3d_tet(F, R), -1);
  EXPECT_EQ(max_abs_diff(R, Mat3::identity()), 0.0);
  EXPECT_EQ(polar_3d_tet(Mat3{}, R), -1);
}

TEST(PolarTet, RigidRotationNeedsNoIteration) {
  // F = Q orthogonal up to the rounding of its construction: R = F without iterating (or one
  // iteration when that rounding is above the 1e-15 test).
  std::mt19937_64 rng(5);
  int none = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Mat3 Q = random_rotation(rng);
    Mat3 R;
    const int it = polar_3d_tet(Q, R);
    EXPECT_GE(it, 0);
    EXPECT_LE(it, 1);
    none += it == 0;
    EXPECT_LE(max_abs_diff(R, Q), 1e-15);
  }
  EXPECT_GE(none, 90);
  // The identity to the rounding of Dm Dm^-1 (a block at rest).
  Mat3 Dm;
  Dm(0, 0) = 0.05; Dm(0, 1) = 0.05; Dm(0, 2) = 0.05;
  Dm(1, 1) = 0.05; Dm(1, 2) = 0.05; Dm(2, 2) = 0.05;
  Mat3 R;
  EXPECT_EQ(polar_3d_tet(Dm * inverse(Dm), R), 0);
  EXPECT_LE(max_abs_diff(R, Mat3::identity()), 1e-15);
}

TEST(PolarTet, ReflectionIsInverted) {
  Mat3 F = Mat3::identity();
  F(0, 0) = -1;  // orthogonal, det -1
  Mat3 R;
  EXPECT_EQ(polar_3d_tet(F, R), -1);
}

}  // namespace
}  // namespace cdem
