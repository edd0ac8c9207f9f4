// Grading curve and d_x (SPEC 4) on distributions whose d-values follow exactly from the
// documented convention.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "cdem/analysis/grading.hpp"

namespace cdem {
namespace {

Fragment fragment(double l_bc, double volume) {
  Fragment f{};
  f.l_bc = l_bc;
  f.volume = volume;
  return f;
}

TEST(Grading, TenEqualVolumes) {
  // Sizes 1..10 with equal volumes: passing = 10 % per fragment, so d_x = x / 10 exactly
  // (the smallest size at which passing >= x %), e.g. d50 = 5.
  std::vector<Fragment> f;
  for (int i = 10; i >= 1; --i) f.push_back(fragment(i, 2.0));  // any order
  const Grading g = grading_curve(f, false);
  ASSERT_EQ(g.size.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(g.size[i], i + 1.0);
    EXPECT_DOUBLE_EQ(g.passing_pct[i], 10.0 * (i + 1));
  }
  EXPECT_EQ(g.passing_pct.back(), 100.0);
  for (int j = 0; j < 9; ++j) EXPECT_DOUBLE_EQ(g.d[j], j + 1.0) << "d" << 10 * (j + 1);
  EXPECT_DOUBLE_EQ(g.d40(), 4.0);
  EXPECT_DOUBLE_EQ(g.d80(), 8.0);
  EXPECT_DOUBLE_EQ(size_at_passing(g, 15.0), 1.5);
  EXPECT_DOUBLE_EQ(size_at_passing(g, 100.0), 10.0);
  EXPECT_EQ(g.excluded, -1);
  EXPECT_EQ(g.total_volume, 20.0);
}

TEST(Grading, LinearInterpolationAndFirstFragmentRule) {
  // Sizes 1, 2, 3, 4, equal volumes: points (1, 25) (2, 50) (3, 75) (4, 100).
  const std::vector<Fragment> f{fragment(3, 1), fragment(1, 1), fragment(4, 1), fragment(2, 1)};
  const Grading g = grading_curve(f, false);
  const double expected[9] = {1.0, 1.0, 1.2, 1.6, 2.0, 2.4, 2.8, 3.2, 3.6};
  for (int j = 0; j < 9; ++j) EXPECT_NEAR(g.d[j], expected[j], 1e-12) << "d" << 10 * (j + 1);
}

TEST(Grading, ExcludesTheLargestFragmentByDefault) {
  std::vector<Fragment> f;
  for (int i = 1; i <= 10; ++i) f.push_back(fragment(i, 1.0));
  f.insert(f.begin() + 4, fragment(50.0, 1000.0));  // the intact rock mass
  const Grading g = grading_curve(f);
  EXPECT_EQ(g.excluded, 4);
  ASSERT_EQ(g.size.size(), 10u);
  EXPECT_DOUBLE_EQ(g.d[4], 5.0);  // d50
  const Grading all = grading_curve(f, false);
  EXPECT_EQ(all.size.back(), 50.0);
  EXPECT_GT(all.d[0], 10.0);  // the big one dominates the volume: d10 is on its segment
  // Excluding a chosen fragment instead (e.g. the one touching a fixed boundary).
  const Grading chosen = grading_curve_excluding(f, 0);
  EXPECT_EQ(chosen.size.front(), 2.0);
  EXPECT_THROW(grading_curve_excluding(f, 11), std::invalid_argument);
}

TEST(Grading, EqualSizesMakeOnePoint) {
  // Two fragments of size 2 (volumes 1 and 3) and one of size 1 (volume 4): passing at 2 is
  // 100 %, at 1 is 50 %; d50 = 1, d75 = 1.5.
  const std::vector<Fragment> f{fragment(2, 1), fragment(1, 4), fragment(2, 3)};
  const Grading g = grading_curve(f, false);
  ASSERT_EQ(g.size.size(), 2u);
  EXPECT_EQ(g.passing_pct[0], 50.0);
  EXPECT_EQ(g.passing_pct[1], 100.0);
  EXPECT_EQ(g.d[4], 1.0);
  EXPECT_DOUBLE_EQ(size_at_passing(g, 75.0), 1.5);
}

TEST(Grading, EmptyCurveGivesNaN) {
  const std::vector<Fragment> one{fragment(3, 5)};
  const Grading g = grading_curve(one);  // the only fragment is the rock mass
  EXPECT_TRUE(g.size.empty());
  for (const double d : g.d) EXPECT_TRUE(std::isnan(d));
  EXPECT_TRUE(std::isnan(grading_curve({}).d80()));
  const std::vector<Fragment> zero{fragment(1, 0), fragment(2, 0)};
  EXPECT_TRUE(grading_curve(zero, false).size.empty());
}

}  // namespace
}  // namespace cdem
