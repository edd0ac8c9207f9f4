// The cost-balanced thread ranges of the step's loops (core/loop_split.hpp): the ranges cover the
// loop once, contiguously, at any thread count; driven with synthetic times, the cuts move to
// where the threads' times are equal and stay there; a new thread count starts from equal counts;
// loops too short to time leave the cuts alone. That results do not depend on the cuts is the
// determinism tests' part (test_determinism.cpp, test_contact.cpp: 1 against 2 threads).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "cdem/core/loop_split.hpp"

namespace cdem {
namespace {

// Every index of [0, n) in exactly one thread's range, the ranges in thread order.
void expect_cover(const LoopSplit& s, int threads, std::int64_t n) {
  std::int64_t next = 0;
  for (int t = 0; t < threads; ++t) {
    const auto [lo, hi] = s.range(t, threads, n);
    EXPECT_EQ(lo, next) << "thread " << t << " of " << threads << ", n = " << n;
    EXPECT_LE(lo, hi);
    next = hi;
  }
  EXPECT_EQ(next, n);
}

// The threads' times for their ranges when item i costs cost(i) seconds.
template <class F>
std::vector<double> times_of(const LoopSplit& s, int threads, std::int64_t n, F cost) {
  std::vector<double> t(static_cast<std::size_t>(threads), 0.0);
  for (int k = 0; k < threads; ++k) {
    const auto [lo, hi] = s.range(k, threads, n);
    for (std::int64_t i = lo; i < hi; ++i) t[static_cast<std::size_t>(k)] += cost(i);
  }
  return t;
}

template <class F>
void run_loop(LoopSplit& s, int threads, std::int64_t n, F cost) {
  const auto t = times_of(s, threads, n, cost);
  for (int k = 0; k < threads; ++k) s.record(k, threads, t[static_cast<std::size_t>(k)]);
  s.update();
}

double imbalance(const std::vector<double>& t) {
  double sum = 0, mx = 0;
  for (double x : t) sum += x, mx = std::max(mx, x);
  return mx / (sum / static_cast<double>(t.size()));
}

TEST(LoopSplit, RangesCoverTheLoopOnce) {
  LoopSplit s;
  for (int threads = 1; threads <= 5; ++threads)
    for (std::int64_t n : {0, 1, 2, 3, 7, 1000, 1001}) expect_cover(s, threads, n);
  // after the cuts have moved, too
  auto cost = [](std::int64_t i) { return i < 300 ? 4e-6 : 1e-6; };
  for (int it = 0; it < 10; ++it) run_loop(s, 3, 1000, cost);
  for (std::int64_t n : {0, 1, 2, 999, 1000, 100000}) expect_cover(s, 3, n);
  // more threads than the table holds: equal counts
  expect_cover(s, LoopSplit::kMaxThreads + 3, 10000);
}

TEST(LoopSplit, CutsMoveToEqualTimes) {
  LoopSplit s;
  const std::int64_t n = 10000;
  // the first 30 % of the items cost 5 times the rest (a broken zone in a long run)
  auto cost = [](std::int64_t i) { return i < 3000 ? 5e-7 : 1e-7; };
  for (int threads : {2, 3, 4}) {
    run_loop(s, threads, n, cost);  // (a new count: equal counts first)
    const double before = imbalance(times_of(s, threads, n, cost));
    EXPECT_GT(before, 1.3) << threads;
    for (int it = 0; it < 30; ++it) run_loop(s, threads, n, cost);
    // within a few items' cost of equal: the cuts halve their distance to the target each time
    const double after = imbalance(times_of(s, threads, n, cost));
    EXPECT_LT(after, 1.01) << threads << " threads: " << before << " -> " << after;
    for (int k = 1; k < threads; ++k) EXPECT_LT(s.cut(k - 1), s.cut(k));
  }
}

TEST(LoopSplit, FollowsASlowerThread) {
  // Equal items, but thread 1 runs at half speed (a core shared with other work): it ends with
  // a third of the items, and both threads take the same time.
  LoopSplit s;
  const std::int64_t n = 9000;
  for (int it = 0; it < 40; ++it) {
    const auto [lo0, hi0] = s.range(0, 2, n);
    const auto [lo1, hi1] = s.range(1, 2, n);
    s.record(0, 2, 1e-6 * static_cast<double>(hi0 - lo0));
    s.record(1, 2, 2e-6 * static_cast<double>(hi1 - lo1));
    s.update();
  }
  EXPECT_NEAR(s.cut(1), 2.0 / 3.0, 0.01);
}

TEST(LoopSplit, ShortLoopsAndOneThreadLeaveTheCuts) {
  LoopSplit s;
  auto cheap = [](std::int64_t i) { return i < 50 ? 1e-9 : 1e-10; };  // 55 ns in all
  for (int it = 0; it < 10; ++it) run_loop(s, 2, 100, cheap);
  EXPECT_DOUBLE_EQ(s.cut(1), 0.5);
  LoopSplit one;
  for (int it = 0; it < 10; ++it) run_loop(one, 1, 100, [](std::int64_t) { return 1.0; });
  const auto [lo, hi] = one.range(0, 1, 100);
  EXPECT_EQ(lo, 0);
  EXPECT_EQ(hi, 100);
  // a thread with nothing to do keeps a share: the range never collapses to nothing
  LoopSplit z;
  for (int it = 0; it < 50; ++it) run_loop(z, 2, 1000, [](std::int64_t i) { return i < 50 ? 1e-3 : 0.0; });
  EXPECT_NEAR(z.cut(1), 0.1, 1e-12);
}

TEST(LoopSplit, InAParallelRegion) {
  // begin / end in a real region: each index visited once whatever the cuts, for 1 and 2
  // threads, and the counts summed by a reduction come out the same.
  LoopSplit s;
  const std::int64_t n = 100000;
  std::vector<int> seen(static_cast<std::size_t>(n));
  for (int threads : {1, 2, 2, 2, 1, 2}) {
    std::fill(seen.begin(), seen.end(), 0);
    std::int64_t count = 0;
#pragma omp parallel num_threads(threads) reduction(+ : count)
    {
      const LoopSplit::Range r = s.begin(n);
      for (std::int64_t i = r.lo; i < r.hi; ++i) {
        ++seen[static_cast<std::size_t>(i)];
        count += i % 3 == 0;
      }
      s.end(r);
    }
    s.update();
    EXPECT_EQ(count, (n + 2) / 3);
    EXPECT_EQ(*std::min_element(seen.begin(), seen.end()), 1);
    EXPECT_EQ(*std::max_element(seen.begin(), seen.end()), 1);
  }
}

TEST(LoopSplit, RunAndRunReduce) {
  // The one-call forms: run visits each index once; run_reduce joins the threads' counts and
  // maxima into the exact totals, for 1 to 3 threads and loops shorter than the thread count.
  LoopSplit s;
  const int before = omp_get_max_threads();
  for (const std::int64_t n : {std::int64_t{0}, std::int64_t{1}, std::int64_t{2}, std::int64_t{100000}}) {
    std::vector<int> seen(static_cast<std::size_t>(n));
    for (int threads : {1, 2, 3, 2}) {
      omp_set_num_threads(threads);
      std::fill(seen.begin(), seen.end(), 0);
      s.run(n, [&](const LoopSplit::Range& r) {
        for (std::int64_t i = r.lo; i < r.hi; ++i) ++seen[static_cast<std::size_t>(i)];
      });
      for (std::int64_t i = 0; i < n; ++i) ASSERT_EQ(seen[static_cast<std::size_t>(i)], 1) << "n " << n << ", index " << i;
      const LoopSplit::CountMax cm = s.run_reduce(n, LoopSplit::CountMax{}, [&](const LoopSplit::Range& r) {
        LoopSplit::CountMax c;
        for (std::int64_t i = r.lo; i < r.hi; ++i) {
          c.count += i % 3 == 0;
          c.max = std::max(c.max, static_cast<double>(i % 1000) * 0.5);
        }
        return c;
      }, LoopSplit::CountMax::join);
      EXPECT_EQ(cm.count, (n + 2) / 3);
      EXPECT_EQ(cm.max, n == 0 ? 0.0 : static_cast<double>(std::min<std::int64_t>(n - 1, 999)) * 0.5);
    }
  }
  omp_set_num_threads(before);
}

}  // namespace
}  // namespace cdem

namespace cdem {
namespace {

// CountMax's join runs in the order the threads finish (a critical section): it must not depend
// on it. The maximum's place is the least index among equal maxima, whichever range reports first.
TEST(LoopSplit, CountMaxJoinIgnoresTheOrder) {
  using CM = LoopSplit::CountMax;
  const std::vector<CM> parts = {{3, 0.5, 7}, {2, 0.9, 40}, {0, 0.0, -1}, {4, 0.9, 12}, {1, 0.2, 90}};
  std::vector<int> order = {0, 1, 2, 3, 4};
  do {
    CM all;
    for (int k : order) all = CM::join(all, parts[static_cast<std::size_t>(k)]);
    EXPECT_EQ(all.count, 10);
    EXPECT_EQ(all.max, 0.9);
    EXPECT_EQ(all.at, 12);
  } while (std::next_permutation(order.begin(), order.end()));
  // the maximum found in a parallel loop: the first of equal values in index order, any threads
  std::vector<double> v(10000);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>((i * 7919) % 1000);
  const int threads_before = omp_get_max_threads();
  for (int t : {1, 2, 3}) {
    LoopSplit split;
    omp_set_num_threads(t);
    const CM r = split.run_reduce(static_cast<std::int64_t>(v.size()), CM{}, [&](const LoopSplit::Range& part) {
      CM held;
      for (std::int64_t i = part.lo; i < part.hi; ++i)
        if (v[static_cast<std::size_t>(i)] > held.max) held.max = v[static_cast<std::size_t>(i)], held.at = i;
      return held;
    }, CM::join);
    EXPECT_EQ(r.max, 999.0);
    EXPECT_EQ(r.at, static_cast<std::int64_t>(std::find(v.begin(), v.end(), 999.0) - v.begin())) << t;
  }
  omp_set_num_threads(threads_before);
}

}  // namespace
}  // namespace cdem
