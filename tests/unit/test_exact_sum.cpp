// Order-free sums (core/exact_sum.hpp): the same bits in any order and any split among ranks
// (the ranks simulated here by threads meeting at a barrier, as MPI_Allreduce would), and the
// true sum rounded once to the nearest double.
#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include "cdem/core/exact_sum.hpp"

namespace {

using cdem::ExactInt;
using cdem::SumReducer;
using cdem::sum_exactly;

double sum_of(const std::vector<double>& x) {
  return sum_exactly(1, [&](auto&& put) {
    for (double v : x) put(0, v);
  })[0];
}

// Threads as ranks: each reduction puts every thread's values in its slot, waits for all, and
// takes the sum of the slots.
struct World {
  explicit World(int n) : ranks(n), bar(n), slot(static_cast<std::size_t>(n)) {}
  int ranks;
  std::barrier<> bar;
  std::vector<std::vector<std::int64_t>> slot;
};
World* g_world = nullptr;
thread_local int t_rank = 0;

void reduce(std::int64_t* v, std::size_t n) {
  World& w = *g_world;
  w.slot[static_cast<std::size_t>(t_rank)].assign(v, v + n);
  w.bar.arrive_and_wait();
  for (std::size_t i = 0; i < n; ++i) {
    std::int64_t a = 0;
    for (int r = 0; r < w.ranks; ++r) a += w.slot[static_cast<std::size_t>(r)][i];
    v[i] = a;
  }
  w.bar.arrive_and_wait();
}

// The sums of `x` split into `ranks` interleaved shares (term k to rank k mod ranks, each share
// in reverse order), one per thread; every rank's result.
std::vector<std::vector<double>> split_sum(const std::vector<double>& x, int ranks, std::size_t sums) {
  World w(ranks);
  g_world = &w;
  SumReducer r;
  r.ranks = ranks;
  r.sum = reduce;
  std::vector<std::vector<double>> out(static_cast<std::size_t>(ranks));
  std::vector<std::thread> th;
  for (int q = 0; q < ranks; ++q)
    th.emplace_back([&, q] {
      t_rank = q;
      out[static_cast<std::size_t>(q)] = sum_exactly(sums, [&](auto&& put) {
        for (std::size_t k = x.size(); k-- > 0;)
          if (static_cast<int>(k % static_cast<std::size_t>(ranks)) == q) put(k % sums, x[k]);
      }, &r);
    });
  for (auto& t : th) t.join();
  g_world = nullptr;
  return out;
}

std::vector<double> wide_terms(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mant(-1.0, 1.0);
  std::uniform_int_distribution<int> ex(-60, 60);
  std::vector<double> x(n);
  for (auto& v : x) v = std::ldexp(mant(rng), ex(rng));
  return x;
}

TEST(ExactSum, SameBitsInAnyOrder) {
  std::vector<double> x = wide_terms(20000, 1);
  const double s0 = sum_of(x);
  std::mt19937_64 rng(2);
  double plain_lo = s0, plain_hi = s0;
  for (int k = 0; k < 20; ++k) {
    std::shuffle(x.begin(), x.end(), rng);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(sum_of(x)), std::bit_cast<std::uint64_t>(s0));
    double p = 0;
    for (double v : x) p += v;
    plain_lo = std::min(plain_lo, p), plain_hi = std::max(plain_hi, p);
  }
  // the control: a plain running sum of the same terms does depend on their order
  EXPECT_LT(plain_lo, plain_hi);
}

TEST(ExactSum, SameBitsForAnySplitAmongRanks) {
  const std::vector<double> x = wide_terms(30000, 3);
  const std::size_t sums = 3;
  const auto one = sum_exactly(sums, [&](auto&& put) {
    for (std::size_t k = 0; k < x.size(); ++k) put(k % sums, x[k]);
  });
  for (int ranks : {2, 3, 7}) {
    const auto got = split_sum(x, ranks, sums);
    for (const auto& g : got)
      for (std::size_t i = 0; i < sums; ++i)
        EXPECT_EQ(std::bit_cast<std::uint64_t>(g[i]), std::bit_cast<std::uint64_t>(one[i])) << ranks << " ranks, sum " << i;
  }
}

TEST(ExactSum, TrueSumOfIntegers) {
  // integers below 2^40 times 2^-20: the result is the true sum (an integer below 2^57 times
  // 2^-20, summed here in 128-bit integers) rounded once to a double
  std::mt19937_64 rng(4);
  std::uniform_int_distribution<std::int64_t> d(-(std::int64_t{1} << 40), std::int64_t{1} << 40);
  std::vector<double> x(100000);
  ExactInt exact = 0;
  for (auto& v : x) {
    const std::int64_t k = d(rng);
    exact += k;
    v = std::ldexp(static_cast<double>(k), -20);
  }
  EXPECT_EQ(sum_of(x), std::ldexp(static_cast<double>(exact), -20));
}

TEST(ExactSum, CancellationAndSpecialValues) {
  // a plain sum loses the 1 to rounding; the exact one keeps it
  EXPECT_EQ(sum_of({1e20, 1.0, -1e20}), 1.0);
  EXPECT_EQ(sum_of({-1e20, -1.0, 1e20}), -1.0);
  EXPECT_EQ(sum_of({}), 0.0);
  EXPECT_EQ(sum_of({0.0, -0.0}), 0.0);
  EXPECT_EQ(sum_of({-2.5}), -2.5);
  EXPECT_TRUE(std::isnan(sum_of({1.0, std::numeric_limits<double>::quiet_NaN()})));
  EXPECT_TRUE(std::isnan(sum_of({1.0, std::numeric_limits<double>::infinity()})));
  // the ends of the range: the largest doubles cancel exactly around the smallest one
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_EQ(sum_of({big, tiny, -big}), tiny);
  EXPECT_EQ(sum_of({big, 0.5 * big, -big}), 0.5 * big);
  EXPECT_EQ(sum_of({tiny, tiny, tiny}), 3 * tiny);
  EXPECT_EQ(sum_of({big, big}), std::numeric_limits<double>::infinity());  // (beyond the range)
}

TEST(ExactSum, RoundsOnceToNearestEven) {
  const double u = 0x1p-52;  // the spacing of the doubles at 1
  // half an ulp: a tie, to the even neighbour (1 below, 1 + 2u above)
  EXPECT_EQ(sum_of({1.0, 0.5 * u}), 1.0);
  EXPECT_EQ(sum_of({1.0 + u, 0.5 * u}), 1.0 + 2 * u);
  // just above half an ulp (the excess 200 bits further down): up (a plain running sum of these
  // three gives 1: it rounds the tie first)
  EXPECT_EQ(sum_of({1.0, 0.5 * u, 0x1p-250}), 1.0 + u);
  // just below: down
  EXPECT_EQ(sum_of({1.0, 0.5 * u, -0x1p-250}), 1.0);
  EXPECT_EQ(sum_of({-1.0, -0.5 * u, -0x1p-250}), -1.0 - u);
}

TEST(ExactSum, ExactOverAWideRange) {
  // 53-bit integers times 2^j, j from -40 to 0: multiples of 2^-40 spanning 93 bits, with
  // opposite signs (a plain sum cancels and rounds): the result is the true sum rounded once.
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<std::int64_t> m(-(std::int64_t{1} << 53) + 1, (std::int64_t{1} << 53) - 1);
  std::uniform_int_distribution<int> j(-40, 0);
  std::vector<double> x(100000);
  ExactInt exact = 0;
  for (auto& v : x) {
    const std::int64_t k = m(rng);
    const int e = j(rng);
    exact += static_cast<ExactInt>(k) << (e + 40);
    v = std::ldexp(static_cast<double>(k), e);
  }
  EXPECT_EQ(sum_of(x), std::ldexp(static_cast<double>(exact), -40));
}

}  // namespace
