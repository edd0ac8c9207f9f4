// Blasting funnel (SPEC 4) on synthetic craters cut into lattices of unit blocks, whose
// depth, extents, axial ratio and footage are known by construction.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "cdem/analysis/funnel.hpp"

namespace cdem {
namespace {

// nx x ny x nz unit cubes below the surface z = 0 (3D), or nx x ny unit squares below y = 0
// (2D). Block (i, j, k) has its centroid at (i + 0.5, j + 0.5, -(k + 0.5)) in 3D, and block
// (i, k) at (i + 0.5, -(k + 0.5), 0) in 2D: k counts layers down from the surface.
struct Lattice {
  int dim, nx, ny, nz;
  std::vector<Vec3> centroid;
  std::vector<double> volume, damage;
  std::vector<std::int32_t> fragment;

  Lattice(int dim_, int nx_, int ny_, int nz_) : dim(dim_), nx(nx_), ny(ny_), nz(nz_) {
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          centroid.push_back(dim == 3 ? Vec3{i + 0.5, j + 0.5, -(k + 0.5)}
                                      : Vec3{i + 0.5, -(k + 0.5), 0.0});
          volume.push_back(1.0);
          damage.push_back(0.0);
          fragment.push_back(0);
        }
  }
  std::size_t id(int i, int j, int k) const {
    return static_cast<std::size_t>(i + nx * (j + ny * k));
  }
  // Breaks the blocks i in [i0, i1), j in [j0, j1) of layer k: every third one by detaching
  // it (another fragment), the others by full damage.
  void break_box(int i0, int i1, int j0, int j1, int k) {
    int c = 0;
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i, ++c) {
        if (c % 3 == 2)
          fragment[id(i, j, k)] = 7;
        else
          damage[id(i, j, k)] = 1.0;
      }
  }
  FunnelInput input() const {
    FunnelInput in;
    in.centroid = centroid;
    in.volume = volume;
    in.damage = damage;
    in.fragment_of_block = fragment;
    in.main_fragment = 0;
    in.up = dim == 3 ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
    in.surface_level = 0.0;
    in.dim = dim;
    return in;
  }
};

// A stepped cone: layer 0 broken over 5 x 3 blocks, layer 1 over 3 x 1, layer 2 over the
// single block on the hole axis. Broken zone: depth 3, l_x 5, l_y 3, e = 0.6, footage 3.
Lattice stepped_crater() {
  Lattice L(3, 12, 10, 8);
  L.break_box(3, 8, 2, 5, 0);
  L.break_box(4, 7, 3, 4, 1);
  L.break_box(5, 6, 3, 4, 2);
  return L;
}

TEST(Funnel, SteppedCrater3D) {
  const Lattice L = stepped_crater();
  FunnelInput in = L.input();
  in.holes.push_back({Vec3{5.5, 3.5, 0.0}, Vec3{0, 0, -1}});
  const Funnel f = blasting_funnel(in);
  EXPECT_EQ(f.typical_size, 1.0);
  EXPECT_EQ(f.broken_blocks, 15 + 3 + 1);
  EXPECT_EQ(f.broken_volume, 19.0);
  EXPECT_DOUBLE_EQ(f.depth, 3.0);
  EXPECT_DOUBLE_EQ(f.l_x, 5.0);
  EXPECT_DOUBLE_EQ(f.l_y, 3.0);
  EXPECT_DOUBLE_EQ(f.axial_ratio, 0.6);
  ASSERT_EQ(f.footage_per_hole.size(), 1u);
  EXPECT_DOUBLE_EQ(f.footage_per_hole[0], 3.0);
  EXPECT_DOUBLE_EQ(f.footage, 3.0);
}

TEST(Funnel, ChosenHorizontalAxisAndThreshold) {
  Lattice L = stepped_crater();
  FunnelInput in = L.input();
  in.x_axis = Vec3{0, 1, 0};  // l_x along y now
  Funnel f = blasting_funnel(in);
  EXPECT_DOUBLE_EQ(f.l_x, 3.0);
  EXPECT_DOUBLE_EQ(f.l_y, 5.0);
  EXPECT_DOUBLE_EQ(f.axial_ratio, 5.0 / 3.0);
  EXPECT_EQ(f.footage, 0.0);  // no hole
  EXPECT_TRUE(f.footage_per_hole.empty());

  // A damage of 0.99 is not broken at the default threshold 1, but is at 0.9.
  L.damage[L.id(0, 0, 0)] = 0.99;
  in = L.input();
  EXPECT_EQ(blasting_funnel(in).broken_blocks, 19);
  in.damage_threshold = 0.9;
  f = blasting_funnel(in);
  EXPECT_EQ(f.broken_blocks, 20);
  EXPECT_DOUBLE_EQ(f.l_x, 8.0);  // now from x = 0 to x = 8
}

TEST(Funnel, FootageStopsAtFirstGap) {
  // One column broken in layers 0, 1 and 3 (layer 2 intact), under hole A; a second hole B
  // far from any broken block. Footage A = 2 (the walk stops at the gap), B = 0; the depth
  // counts every broken block: 4.
  Lattice L(3, 12, 10, 8);
  L.break_box(2, 3, 2, 3, 0);
  L.break_box(2, 3, 2, 3, 1);
  L.break_box(2, 3, 2, 3, 3);
  FunnelInput in = L.input();
  in.holes.push_back({Vec3{2.5, 2.5, 0.0}, Vec3{0, 0, -2}});  // direction is normalised
  in.holes.push_back({Vec3{9.5, 7.5, 0.0}, Vec3{0, 0, -1}});
  const Funnel f = blasting_funnel(in);
  EXPECT_DOUBLE_EQ(f.depth, 4.0);
  EXPECT_DOUBLE_EQ(f.l_x, 1.0);
  EXPECT_DOUBLE_EQ(f.l_y, 1.0);
  ASSERT_EQ(f.footage_per_hole.size(), 2u);
  EXPECT_DOUBLE_EQ(f.footage_per_hole[0], 2.0);
  EXPECT_EQ(f.footage_per_hole[1], 0.0);
  EXPECT_DOUBLE_EQ(f.footage, 1.0);
}

TEST(Funnel, NearAxisBlocksCarryTheFootage) {
  // The block on the axis in layer 1 is intact, but its neighbour 1 m away (within 1.5 h)
  // is broken: the broken zone along the hole is continuous down to 3 m. A block 2 m from
  // the axis does not count: breaking only that one in layer 1 stops the walk at 1 m.
  Lattice L(3, 12, 10, 8);
  L.break_box(5, 6, 5, 6, 0);
  L.break_box(6, 7, 5, 6, 1);
  L.break_box(5, 6, 5, 6, 2);
  FunnelInput in = L.input();
  in.holes.push_back({Vec3{5.5, 5.5, 0.0}, Vec3{0, 0, -1}});
  EXPECT_DOUBLE_EQ(blasting_funnel(in).footage, 3.0);

  Lattice M(3, 12, 10, 8);
  M.break_box(5, 6, 5, 6, 0);
  M.break_box(7, 8, 5, 6, 1);
  M.break_box(5, 6, 5, 6, 2);
  in = M.input();
  in.holes.push_back({Vec3{5.5, 5.5, 0.0}, Vec3{0, 0, -1}});
  EXPECT_DOUBLE_EQ(blasting_funnel(in).footage, 1.0);
}

TEST(Funnel, SteppedCrater2D) {
  // Plane strain: rows of 5, 3 and 1 broken squares under a hole at x = 4.5.
  Lattice L(2, 10, 1, 6);
  L.break_box(2, 7, 0, 1, 0);
  L.break_box(3, 6, 0, 1, 1);
  L.break_box(4, 5, 0, 1, 2);
  FunnelInput in = L.input();
  in.holes.push_back({Vec3{4.5, 0.0, 0.0}, Vec3{0, -1, 0}});
  const Funnel f = blasting_funnel(in);
  EXPECT_EQ(f.broken_blocks, 9);
  EXPECT_DOUBLE_EQ(f.depth, 3.0);
  EXPECT_DOUBLE_EQ(f.l_x, 5.0);
  EXPECT_EQ(f.l_y, 0.0);
  EXPECT_EQ(f.axial_ratio, 0.0);
  EXPECT_DOUBLE_EQ(f.footage, 3.0);
}

TEST(Funnel, NothingBrokenAndBadInput) {
  const Lattice L(3, 4, 4, 4);
  FunnelInput in = L.input();
  in.holes.push_back({Vec3{2, 2, 0}, Vec3{0, 0, -1}});
  const Funnel f = blasting_funnel(in);
  EXPECT_EQ(f.broken_blocks, 0);
  EXPECT_EQ(f.depth, 0.0);
  EXPECT_EQ(f.l_x, 0.0);
  EXPECT_EQ(f.axial_ratio, 0.0);
  EXPECT_EQ(f.footage, 0.0);

  in.holes[0].second = Vec3{};
  EXPECT_THROW(blasting_funnel(in), std::invalid_argument);
  in = L.input();
  in.damage = in.damage.first(10);
  EXPECT_THROW(blasting_funnel(in), std::invalid_argument);
  in = L.input();
  in.up = Vec3{};
  EXPECT_THROW(blasting_funnel(in), std::invalid_argument);
}

}  // namespace
}  // namespace cdem
