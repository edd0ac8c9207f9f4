// The fracture-energy law's elastic branch (fe_elastic, physics/springs.hpp), the test the
// springs mode's fast path rests on, against the law itself (update_spring_point): for random
// intact points (damage state, offsets, forces, motion) near and across their strength, wherever
// fe_elastic says "elastic" the full update must give exactly the fast path's result: F_n =
// k_n (d_n + g0 - d_dil - w) and F_s rotated and incremented, bit for bit, with the damage state
// and the point's state unchanged. Both outcomes must occur often, or this would test nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "cdem/physics/springs.hpp"

namespace cdem {
namespace {

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(FractureEnergyElasticBranch, FastPathEqualsTheLaw) {
  std::mt19937_64 gen(4122026);
  std::uniform_real_distribution<double> u(-1.0, 1.0), u01(0.0, 1.0);
  SpringLaw law;
  law.law = InterfaceLaw::FractureEnergy;
  law.ft = 8e6;
  law.c = 20e6;
  law.tan_phi = std::tan(35.0 * 3.14159265358979323846 / 180.0);
  law.tan_phi_r = 0.5;
  law.tan_psi = 0.25;
  law.wc = 2 * 70 / law.ft;
  law.sc = 2 * 700 / law.c;
  int elastic = 0, other = 0;
  for (int k = 0; k < 20000; ++k) {
    const double area = 1e-3 * (0.5 + u01(gen)), kn = 1e12 * area, ks = 0.4 * kn;
    SpringPoint sp{kn, ks, area, 0.0, Vec3{}, 0.0, 0.0, 0.0, kIntact, 0, 0.0f, 0.0, 0.0};
    // damage: none, some, or nearly full in tension or shear
    const int kind = k % 4;
    sp.w = kind == 1 ? law.wc * u01(gen) : (kind == 3 ? law.wc * (0.9 + 0.1 * u01(gen)) : 0.0);
    sp.slip = kind == 2 ? law.sc * u01(gen) : 0.0;
    sp.dil = sp.slip * law.tan_psi;
    sp.g0 = 1e-7 * u(gen);
    // forces and motion around the strength: openings up to ~2 x f_t A / k_n
    const double d_scale = 2.0 * law.ft * area / kn;
    Vec3 n{u(gen), u(gen), u(gen)};
    n = (1.0 / std::sqrt(dot(n, n))) * n;
    const Vec3 d = Vec3{u(gen), u(gen), u(gen)} * d_scale;
    const Vec3 du = Vec3{u(gen), u(gen), u(gen)} * (0.3 * d_scale);
    sp.fs = Vec3{u(gen), u(gen), u(gen)} * (0.6 * law.c * area);
    sp.fn = kn * (dot(d, n) + sp.g0 - sp.dil - sp.w);
    // the fast path's result (springs.cpp, spring_interface / spring_chunk)
    Vec3 fs = sp.fs;
    const double fs_old2 = dot(fs, fs);
    fs -= dot(fs, n) * n;
    const double fs_proj2 = dot(fs, fs);
    if (fs_proj2 > 0) fs *= std::sqrt(fs_old2 / fs_proj2);
    fs += ks * (du - dot(du, n) * n);
    const double fn = kn * (((dot(d, n) + sp.g0) - sp.dil) - sp.w);
    const bool fast = fe_elastic(law, area, sp.w, sp.slip, fn, dot(fs, fs));
    SpringPoint full = sp;
    update_spring_point(full, law, d, du, n, 0.0, 1.0, sp.fn * n + sp.fs);
    if (fast) {
      ++elastic;
      ASSERT_TRUE(same(full.fn, fn)) << "point " << k;
      ASSERT_TRUE(same(full.fs.x, fs.x) && same(full.fs.y, fs.y) && same(full.fs.z, fs.z)) << "point " << k;
      ASSERT_TRUE(same(full.w, sp.w) && same(full.slip, sp.slip) && same(full.dil, sp.dil)) << "point " << k;
      ASSERT_EQ(full.state, kIntact) << "point " << k;
    } else {
      ++other;
    }
  }
  std::printf("[fe elastic] %d elastic, %d softening or breaking of 20000\n", elastic, other);
  EXPECT_GT(elastic, 2000);
  EXPECT_GT(other, 2000);
}

}  // namespace
}  // namespace cdem
