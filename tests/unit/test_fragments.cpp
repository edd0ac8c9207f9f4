// Fragments (SPEC 4, eq. 17) on hand-built block grids whose answers are exact.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "cdem/analysis/fragments.hpp"

namespace cdem {
namespace {

// Unit cubes (3D) or unit squares x 1 m (2D) on an nx x ny x nz grid; block (i, j, k) has
// index i + nx (j + ny k) and occupies [i, i+1] x [j, j+1] x [k, k+1].
struct Grid {
  int nx, ny, nz;
  std::vector<double> volume;
  std::vector<Vec3> bmin, bmax, centroid, velocity;

  Grid(int nx_, int ny_, int nz_) : nx(nx_), ny(ny_), nz(nz_) {
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const Vec3 lo{double(i), double(j), double(k)};
          volume.push_back(1.0);
          bmin.push_back(lo);
          bmax.push_back(lo + Vec3{1, 1, 1});
          centroid.push_back(lo + Vec3{0.5, 0.5, 0.5});
          velocity.push_back(Vec3{double(i), 0, 0});
        }
  }
  std::int32_t id(int i, int j, int k) const { return i + nx * (j + ny * k); }
  BlockGeometry geometry() const { return {volume, bmin, bmax, centroid, velocity}; }
  // Every face-neighbour pair, in grid order.
  std::vector<Bond> all_bonds() const {
    std::vector<Bond> b;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          if (i + 1 < nx) b.push_back({id(i, j, k), id(i + 1, j, k)});
          if (j + 1 < ny) b.push_back({id(i, j, k), id(i, j + 1, k)});
          if (k + 1 < nz) b.push_back({id(i, j, k), id(i, j, k + 1)});
        }
    return b;
  }
};

// 2 x 2 x 1 grid: blocks 0 (0,0), 1 (1,0), 2 (0,1), 3 (1,1).
TEST(Fragments, IntactGridIsOneFragment) {
  const Grid g(2, 2, 1);
  const auto bonds = g.all_bonds();
  ASSERT_EQ(bonds.size(), 4u);
  const FragmentResult r = find_fragments(g.geometry(), bonds, 3);
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_EQ(r.fragment_of_block, (std::vector<std::int32_t>{0, 0, 0, 0}));
  const Fragment& f = r.fragments[0];
  EXPECT_EQ(f.volume, 4.0);
  EXPECT_EQ(f.blocks, 4);
  EXPECT_EQ(f.l_max, 2.0);
  EXPECT_DOUBLE_EQ(f.l_bc, 0.5 * (std::cbrt(4.0) + 2.0));
  EXPECT_EQ(f.bbox_min.x, 0.0);
  EXPECT_EQ(f.bbox_max.x, 2.0);
  EXPECT_EQ(f.bbox_max.y, 2.0);
  EXPECT_EQ(f.bbox_max.z, 1.0);
  EXPECT_DOUBLE_EQ(f.centroid.x, 1.0);
  EXPECT_DOUBLE_EQ(f.centroid.y, 1.0);
  EXPECT_DOUBLE_EQ(f.centroid.z, 0.5);
  EXPECT_DOUBLE_EQ(f.velocity.x, 0.5);  // blocks move at x velocity 0, 1, 0, 1
}

TEST(Fragments, OneBlockBrokenOff) {
  const Grid g(2, 2, 1);
  // Bonds 1-3 and 2-3 broken: block 3 is alone.
  const std::vector<Bond> bonds{{0, 1}, {0, 2}};
  const FragmentResult r = find_fragments(g.geometry(), bonds, 3);
  ASSERT_EQ(r.fragments.size(), 2u);
  EXPECT_EQ(r.fragment_of_block, (std::vector<std::int32_t>{0, 0, 0, 1}));
  const Fragment& big = r.fragments[0];
  EXPECT_EQ(big.volume, 3.0);
  EXPECT_EQ(big.blocks, 3);
  EXPECT_EQ(big.l_max, 2.0);
  EXPECT_DOUBLE_EQ(big.l_bc, 0.5 * (std::cbrt(3.0) + 2.0));
  EXPECT_DOUBLE_EQ(big.centroid.x, 2.5 / 3.0);
  EXPECT_DOUBLE_EQ(big.centroid.y, 2.5 / 3.0);
  EXPECT_DOUBLE_EQ(big.velocity.x, 1.0 / 3.0);
  const Fragment& small = r.fragments[1];
  EXPECT_EQ(small.volume, 1.0);
  EXPECT_EQ(small.blocks, 1);
  EXPECT_EQ(small.l_max, 1.0);
  EXPECT_EQ(small.l_bc, 1.0);  // (1^(1/3) + 1) / 2
  EXPECT_EQ(small.centroid.x, 1.5);
  EXPECT_EQ(small.centroid.y, 1.5);
  EXPECT_EQ(small.velocity.x, 1.0);
}

TEST(Fragments, EqualVolumesOrderedBySmallestBlock) {
  const Grid g(2, 2, 1);
  // Columns {0, 2} and {1, 3}: equal volumes; the one holding block 0 comes first, whatever
  // the bond order.
  std::vector<Bond> bonds{{3, 1}, {2, 0}};
  FragmentResult r = find_fragments(g.geometry(), bonds, 3);
  EXPECT_EQ(r.fragment_of_block, (std::vector<std::int32_t>{0, 1, 0, 1}));
  ASSERT_EQ(r.fragments.size(), 2u);
  EXPECT_EQ(r.fragments[0].l_max, 2.0);
  EXPECT_DOUBLE_EQ(r.fragments[0].l_bc, 0.5 * (std::cbrt(2.0) + 2.0));
  // No bonds: four single blocks, ids = block indices.
  r = find_fragments(g.geometry(), {}, 3);
  EXPECT_EQ(r.fragment_of_block, (std::vector<std::int32_t>{0, 1, 2, 3}));
  for (const Fragment& f : r.fragments) EXPECT_EQ(f.l_bc, 1.0);
}

TEST(Fragments, LargerVolumeFirst) {
  Grid g(2, 2, 1);
  g.volume[3] = 5.0;  // a heavy single block outranks the three-block fragment
  const std::vector<Bond> bonds{{0, 1}, {0, 2}};
  const FragmentResult r = find_fragments(g.geometry(), bonds, 3);
  EXPECT_EQ(r.fragment_of_block, (std::vector<std::int32_t>{1, 1, 1, 0}));
  EXPECT_EQ(r.fragments[0].volume, 5.0);
  EXPECT_EQ(r.fragments[1].volume, 3.0);
  const std::vector<std::int32_t> boundary{0, 1};
  EXPECT_EQ(largest_fragment_of(r, boundary), 1);
  const std::vector<std::int32_t> all{0, 1, 2, 3};
  EXPECT_EQ(largest_fragment_of(r, all), 0);
  EXPECT_EQ(largest_fragment_of(r, {}), -1);
}

TEST(Fragments, TwoDimensionalAnalogueUsesArea) {
  // 2 x 2 unit squares (area x 1 m): the box's z side (1 m thickness) is not counted.
  Grid g(2, 2, 1);
  const FragmentResult r = find_fragments(g.geometry(), g.all_bonds(), 2);
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_EQ(r.fragments[0].l_max, 2.0);
  EXPECT_EQ(r.fragments[0].l_bc, 2.0);  // (sqrt(4) + 2) / 2
  // A 1 x 3 strip: L_max = 3, L_bc = (sqrt(3) + 3) / 2; the thickness never wins.
  Grid strip(1, 3, 1);
  const FragmentResult s = find_fragments(strip.geometry(), strip.all_bonds(), 2);
  EXPECT_EQ(s.fragments[0].l_max, 3.0);
  EXPECT_DOUBLE_EQ(s.fragments[0].l_bc, 0.5 * (std::sqrt(3.0) + 3.0));
  EXPECT_EQ(characteristic_size(9.0, 3.0, 2), 3.0);
  EXPECT_EQ(characteristic_size(8.0, 4.0, 3), 3.0);
}

TEST(Fragments, DeterministicUnderBondPermutation) {
  const Grid g(10, 8, 6);
  std::vector<Bond> bonds = g.all_bonds();
  std::mt19937 rng(42);
  std::vector<Bond> kept;
  for (const Bond& b : bonds)
    if (rng() % 100 < 35) kept.push_back(b);  // a sparse set: many fragments
  const FragmentResult r1 = find_fragments(g.geometry(), kept, 3);
  std::shuffle(kept.begin(), kept.end(), rng);
  for (Bond& b : kept)
    if (rng() % 2) std::swap(b.a, b.b);
  const FragmentResult r2 = find_fragments(g.geometry(), kept, 3);
  EXPECT_GT(r1.fragments.size(), 10u);
  EXPECT_EQ(r1.fragment_of_block, r2.fragment_of_block);
  ASSERT_EQ(r1.fragments.size(), r2.fragments.size());
  double total = 0.0;
  for (std::size_t i = 0; i < r1.fragments.size(); ++i) {
    EXPECT_EQ(r1.fragments[i].volume, r2.fragments[i].volume);
    EXPECT_EQ(r1.fragments[i].blocks, r2.fragments[i].blocks);
    if (i > 0) {
      EXPECT_GE(r1.fragments[i - 1].volume, r1.fragments[i].volume);
    }
    total += r1.fragments[i].volume;
  }
  EXPECT_EQ(total, 480.0);
}

TEST(Fragments, RejectsBadInput) {
  const Grid g(2, 2, 1);
  const std::vector<Bond> bad{{0, 4}};
  EXPECT_THROW(find_fragments(g.geometry(), bad, 3), std::invalid_argument);
  EXPECT_THROW(find_fragments(g.geometry(), {}, 1), std::invalid_argument);
  BlockGeometry short_geometry = g.geometry();
  short_geometry.velocity = short_geometry.velocity.first(3);
  EXPECT_THROW(find_fragments(short_geometry, {}, 3), std::invalid_argument);
  Grid negative(2, 2, 1);
  negative.volume[1] = -1.0;
  EXPECT_THROW(find_fragments(negative.geometry(), {}, 3), std::invalid_argument);
}

// Not a pass/fail test: prints the time of find_fragments on 100k blocks and 300k bonds (a
// 50 x 50 x 40 grid with 70 % or 25 % of its face bonds intact, shuffled, padded to 300k with
// duplicates as several interfaces may join the same two blocks).
TEST(Fragments, TimingHundredThousandBlocks) {
  const Grid g(50, 50, 40);
  ASSERT_EQ(g.volume.size(), 100000u);
  for (const unsigned intact_pct : {70u, 25u}) {
    std::vector<Bond> bonds = g.all_bonds();
    std::mt19937 rng(7);
    std::shuffle(bonds.begin(), bonds.end(), rng);
    std::vector<Bond> kept;
    for (const Bond& b : bonds)
      if (rng() % 100 < intact_pct) kept.push_back(b);
    while (kept.size() < 300000) kept.push_back(kept[rng() % kept.size()]);
    double best = 1e30;
    std::size_t fragments = 0;
    for (int rep = 0; rep < 5; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      const FragmentResult r = find_fragments(g.geometry(), kept, 3);
      const auto t1 = std::chrono::steady_clock::now();
      best = std::min(best, std::chrono::duration<double, std::milli>(t1 - t0).count());
      fragments = r.fragments.size();
    }
    std::printf(
        "[timing] find_fragments: %zu blocks, %zu bonds (%u %% of face bonds intact) "
        "-> %zu fragments in %.2f ms (best of 5)\n",
        g.volume.size(), kept.size(), intact_pct, fragments, best);
  }
}

}  // namespace
}  // namespace cdem
