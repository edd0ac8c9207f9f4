// The vectorised tet kernel (block_forces_tet: chunks of 8 blocks, one per SIMD lane, the Newton
// polar iteration masked per lane) against the one-block-at-a-time reference
// (block_forces_tet_reference). The chunked kernel writes every operation out, with the fused
// multiply-adds where GCC fused them in the reference on the machine it was written on, so the
// two agree there bit for bit and elsewhere to round-off (checked to 1e-13, below):
// nodal forces (with the spring gather), Cauchy stress, strain energy, volume ratio, the
// inverted count and the first inverted block.
//
// States: a tet box under a per-vertex random displacement of growing size (strains from 0 to
// ~0.3, so the polar iteration takes 0 to ~5 steps), on a rigid rotation, with and without an
// in-situ stress, a few blocks inverted by a node pushed through the opposite face, and ranges
// that do not start or end on a chunk boundary (the partial chunks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cdem/physics/block_forces.hpp"
#include "cdem/physics/springs.hpp"
#include "model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;

// Agreement to round-off: every entry within 1e-13 of the array's largest magnitude. The chunked
// kernel's roundings are fixed (contraction off, explicit fused multiply-adds); the reference's
// are GCC's contraction for the build's target, so the two agreed bit for bit on one CPU kind
// (AVX-512, GCC 12 -march=native) and differ in the last bits on another (AVX-512 FP16, where
// -march=native is another target): measured at most 3e-20 of the largest force there. A
// wrong term would differ by far more than 1e-13.
double max_abs(double x) { return std::abs(x); }
double max_abs(const Vec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); }
double max_abs(const Sym6& s) {
  double r = 0;
  for (double x : s) r = std::max(r, std::abs(x));
  return r;
}
template <class T>
double diff_abs(const T& a, const T& b);
template <>
double diff_abs(const double& a, const double& b) { return std::abs(a - b); }
template <>
double diff_abs(const Vec3& a, const Vec3& b) { return max_abs(a - b); }
template <>
double diff_abs(const Sym6& a, const Sym6& b) {
  double r = 0;
  for (std::size_t k = 0; k < a.size(); ++k) r = std::max(r, std::abs(a[k] - b[k]));
  return r;
}
template <class T>
bool close(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return false;
  double scale = 0, d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    scale = std::max(scale, max_abs(b[i]));
    d = std::max(d, diff_abs(a[i], b[i]));
  }
  return d <= 1e-13 * scale;
}

TEST(TetKernel, VectorisedMatchesReference) {
  const Mesh mesh = tet_box(6, 5, 5, 0.6, 0.5, 0.5);
  Model base = make_model(mesh, rock(), interface_of(InterfaceLaw::MohrCoulomb));
  const Mat3 Q = rotation({1, 2, 3}, 0.3);
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> jitter(base.vertex_X.size());
  for (auto& j : jitter) j = {u(gen), u(gen), u(gen)};
  const auto& g = base.groups.front();
  ASSERT_EQ(g.type, ElemType::Tet4);
  for (double amp : {0.0, 1e-7, 1e-5, 1e-3, 1e-2, 3e-2}) {
    for (bool prestress : {false, true}) {
      Model m = base;
      for (std::size_t n = 0; n < m.n_nodes(); ++n)
        m.x[n] = Q * (m.X(n) + amp * jitter[m.node_vertex[n]]);
      if (prestress)
        for (std::size_t b = 0; b < m.n_blocks(); ++b)
          m.stress0[b] = {-1e6, -2e6, -3e6, 1e5, -2e5, 3e5};
      else
        std::vector<Sym6>().swap(m.stress0);
      // Invert a few blocks: node 0 pushed through the opposite face.
      for (std::int32_t b : {5, 77, 300}) {
        const auto n0 = m.block_first_node[b];
        const Vec3 c = (m.x[n0 + 1] + m.x[n0 + 2] + m.x[n0 + 3]) / 3.0;
        m.x[n0] = c + 2.0 * (c - m.x[n0]);
      }
      // Spring forces to gather (their state as a step leaves it).
      for (std::size_t n = 0; n < m.n_nodes(); ++n) m.v[n] = {u(gen), u(gen), u(gen)};
      spring_forces(m, 1e-6, 0.0);
      // Whole range, and ranges off the chunk boundaries.
      const std::vector<std::pair<std::int32_t, std::int32_t>> ranges = {
          {g.begin, g.end}, {g.begin + 3, g.end - 5}, {g.begin + 17, g.begin + 18}};
      for (auto [b0, b1] : ranges) {
        Model ref = m;
        std::int32_t first = -1, first_ref = -1;
        const auto inv = block_forces_tet(m, b0, b1, &first, true);
        const auto inv_ref = block_forces_tet_reference(ref, b0, b1, &first_ref, true);
        const std::string what = "amplitude " + std::to_string(amp) +
                                 (prestress ? " prestressed" : "") + ", blocks [" +
                                 std::to_string(b0) + ", " + std::to_string(b1) + ")";
        EXPECT_EQ(inv, inv_ref) << what;
        EXPECT_EQ(first, first_ref) << what;
        EXPECT_TRUE(close(m.f, ref.f)) << what << ": nodal forces differ";
        EXPECT_TRUE(close(m.stress, ref.stress)) << what << ": stress differs";
        EXPECT_TRUE(close(m.strain_energy, ref.strain_energy)) << what << ": energy differs";
        EXPECT_TRUE(close(m.vol_ratio, ref.vol_ratio)) << what << ": J differs";
        if (b1 - b0 > 100) {
          EXPECT_GE(inv, 3) << what;  // the three inverted blocks are seen
        }
      }
    }
  }
}

}  // namespace
}  // namespace cdem
