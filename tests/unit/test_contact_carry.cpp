// The in-place carry of the contact pairs' state at a rebuild (carry_monotone, physics/contact.hpp)
// against the plain copy it replaces: for random merges of two sorted pair lists (pairs that
// stay, pairs dropped, new pairs, the new list longer or shorter than the old), each new slot gets
// the old slot's value or the fresh value, exactly (a copy: no tolerance).
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "cdem/physics/contact.hpp"

namespace cdem {
namespace {

// A merge of an old list of n_old pairs into a new one: each old pair stays with probability
// p_stay, and new pairs are inserted between them with probability p_new each.
std::vector<std::int32_t> random_merge(std::mt19937& rng, int n_old, double p_stay, double p_new) {
  std::bernoulli_distribution stay(p_stay), add(p_new);
  std::vector<std::int32_t> from;
  for (int o = 0; o < n_old; ++o) {
    while (add(rng)) from.push_back(-1);
    if (stay(rng)) from.push_back(o);
  }
  while (add(rng)) from.push_back(-1);
  return from;
}

TEST(ContactCarry, InPlaceEqualsCopy) {
  std::mt19937 rng(20261204);
  int cases = 0, longer = 0, shorter = 0;
  for (int n_old : {0, 1, 2, 7, 100, 1000})
    for (double p_stay : {0.0, 0.3, 0.9, 1.0})
      for (double p_new : {0.0, 0.1, 0.5, 0.8})
        for (int rep = 0; rep < 5; ++rep) {
          const std::vector<std::int32_t> from = random_merge(rng, n_old, p_stay, p_new);
          std::vector<double> old(static_cast<std::size_t>(n_old));
          for (int o = 0; o < n_old; ++o) old[static_cast<std::size_t>(o)] = 1000.0 + o;
          std::vector<double> expect(from.size());
          for (std::size_t p = 0; p < from.size(); ++p) expect[p] = from[p] >= 0 ? old[static_cast<std::size_t>(from[p])] : -1.0;
          std::vector<double> v = old;
          carry_monotone(v, from, -1.0);
          ASSERT_EQ(v, expect) << "n_old " << n_old << ", stay " << p_stay << ", new " << p_new;
          ++cases;
          longer += from.size() > old.size();
          shorter += from.size() < old.size();
        }
  // both directions of the shift were exercised
  EXPECT_GT(longer, 50);
  EXPECT_GT(shorter, 50);
  EXPECT_EQ(cases, 6 * 4 * 4 * 5);
}

TEST(ContactCarry, KeepsVectorValues) {
  // a vector type (the forces) and a byte type (the contact face) carried the same way
  std::vector<Vec3> f = {{1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  std::vector<std::int8_t> kf = {0, 1, 2};
  const std::vector<std::int32_t> from = {-1, 0, 2, -1};
  carry_monotone(f, from, Vec3{});
  carry_monotone(kf, from, std::int8_t{-1});
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0].x, 0.0);
  EXPECT_EQ(f[1].x, 1.0);
  EXPECT_EQ(f[2].x, 3.0);
  EXPECT_EQ(f[3].x, 0.0);
  EXPECT_EQ(kf, (std::vector<std::int8_t>{-1, 0, 2, -1}));
}

}  // namespace
}  // namespace cdem
