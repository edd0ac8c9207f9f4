// The edge contacts' vector prefilter (edge_candidates, physics/contact_edges.cpp) against the
// edge-pair test it spares (edge_hit_either): every edge pair the test finds in contact must be
// among the candidates, or a contact would be missed. Exact, no tolerance: the prefilter does
// the test's own operations in its order (the file is compiled without contraction), so it
// rejects only pairs the test rejects, bit for bit, including the ties of aligned meshes (nodes
// on a lattice, faces on faces) and non-finite coordinates (a node that went to NaN).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>

#include "cdem/physics/contact.hpp"

namespace cdem {
namespace {

TetGeom make_tet(const std::array<Vec3, 4>& x, double size) {
  const std::array<Vec3, 4> v{};
  TetGeom g;
  tet_geom_of(x.data(), v.data(), size, g);
  return g;
}

// A tetrahedron with positive orientation (outward face normals, as the model's blocks).
std::array<Vec3, 4> oriented(std::array<Vec3, 4> x) {
  if (dot(cross(x[1] - x[0], x[2] - x[0]), x[3] - x[0]) < 0) std::swap(x[1], x[2]);
  return x;
}

TEST(EdgeCandidates, EveryContactIsACandidate) {
  std::mt19937 rng(20261206);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> lattice(-2, 2), mask(0, 63), kind(0, 5);
  auto jitter = [&](double s) { return Vec3{s * u(rng), s * u(rng), s * u(rng)}; };
  std::int64_t pairs = 0, hits = 0, candidates = 0, tested = 0;
  for (int rep = 0; rep < 200000; ++rep) {
    std::array<Vec3, 4> a, b;
    const int k = kind(rng);
    if (k <= 1) {  // two random tets overlapping or near
      for (auto& p : a) p = jitter(1.0);
      const Vec3 shift = jitter(k == 0 ? 0.5 : 1.5);
      for (int i = 0; i < 4; ++i) b[i] = a[i] + shift + jitter(0.6);
    } else if (k <= 3) {  // nodes on a lattice: shared nodes, faces on faces, exact ties
      for (auto& p : a) p = Vec3{0.5 * lattice(rng), 0.5 * lattice(rng), 0.5 * lattice(rng)};
      for (auto& p : b) p = Vec3{0.5 * lattice(rng), 0.5 * lattice(rng), 0.5 * lattice(rng)};
      if (k == 3) b[0] = a[0], b[1] = a[1];  // an edge shared
    } else if (k == 4) {  // B: A's mirror through a face of A, pressed in a little (face on face)
      for (auto& p : a) p = jitter(1.0);
      const Vec3 n = normalized(cross(a[1] - a[0], a[2] - a[0]));
      b = a;
      b[3] = a[3] - 2.0 * dot(a[3] - a[0], n) * n + jitter(0.05);
      for (auto& p : b) p = p + jitter(1e-3);
    } else {  // a node not finite, or a flat tet
      for (auto& p : a) p = jitter(1.0);
      for (int i = 0; i < 4; ++i) b[i] = a[i] + jitter(0.7);
      if (rng() % 2)
        b[rng() % 4].x = std::numeric_limits<double>::quiet_NaN();
      else
        b[3] = 0.5 * (b[0] + b[1]);
    }
    // (on the lattice, half the cases with no tolerance: nodes exactly on face planes then sit
    // on the inside test's boundary, where a prefilter comparing the other way would differ)
    const bool exact = (k == 2 || k == 3) && rep % 2 == 1;
    const TetGeom A = make_tet(oriented(a), exact ? 0.0 : 1.0), B = make_tet(oriented(b), exact ? 0.0 : 0.8);
    const int ma = rep % 3 == 0 ? 63 : mask(rng), mb = rep % 3 == 0 ? 63 : mask(rng);
    const std::uint64_t cand = edge_candidates(A, ma, B, mb);
    ++pairs;
    for (int ea = 0; ea < 6; ++ea)
      for (int eb = 0; eb < 6; ++eb) {
        const bool in_masks = (ma >> ea & 1) && (mb >> eb & 1);
        const bool is_cand = cand >> (6 * ea + eb) & 1;
        // a candidate is always within the masks
        ASSERT_TRUE(in_masks || !is_cand) << "rep " << rep << " edges " << ea << ", " << eb;
        if (!in_masks) continue;
        ++tested;
        candidates += is_cand;
        EdgeHit h;
        const int role = edge_hit_either(A, ea, B, eb, h);
        hits += role != 0;
        ASSERT_TRUE(role == 0 || is_cand) << "rep " << rep << " edges " << ea << ", " << eb << " kind " << k;
      }
  }
  // The cases must exercise both outcomes: contacts found, and most pairs rejected early.
  EXPECT_GT(hits, 10000) << pairs << " block pairs";
  EXPECT_LT(candidates, tested / 2) << "the prefilter rejects most edge pairs";
  EXPECT_GE(candidates, hits);
  std::printf("%lld block pairs, %lld edge pairs tested: %lld candidates, %lld contacts\n",
              static_cast<long long>(pairs), static_cast<long long>(tested),
              static_cast<long long>(candidates), static_cast<long long>(hits));
}

}  // namespace
}  // namespace cdem
