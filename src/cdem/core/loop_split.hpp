// Contiguous per-thread ranges of a parallel loop whose iterations cost unevenly, cut where the
// threads' measured times put equal work (docs/performance.md, "Threads that share the work").
//
// OpenMP's schedule(static) gives each thread an equal count of iterations. In a fragmented
// model the iterations do not cost alike: the blocks and interfaces of the broken pit cost more
// than those of the intact rock, and the model's order (Hilbert, mesh/reorder) puts them in a few
// long runs. In the late SPEC 5.3 state one thread's half of the spring, tet and cluster loops
// took 35 % longer than the other's, and that thread set the step's pace. Interleaving small
// chunks (schedule(static, k), or dynamic) balanced the counts of costly items but made every
// kernel 30-45 % slower: the hardware prefetcher follows a thread's long contiguous range, not
// a chunk every other one. So the ranges stay contiguous, one per thread, and their cuts move:
// after each run of a loop, the cumulative cost along the index is taken as piecewise linear
// through the threads' times, and each cut moves half way to where that cost splits evenly.
//
// The results never depend on the cuts: a loop split this way must write per iteration only that
// iteration's own elements, and reduce only integers or maxima (which are exact in any order),
// as for schedule(static). The cuts are hints of speed only; no allocation after the first use
// at a thread count (up to kMaxThreads; beyond it, equal counts).
//
//   static LoopSplit split;  // one per loop
//   split.run(n, [&](const LoopSplit::Range& r) {
//     for (std::int64_t i = r.lo; i < r.hi; ++i) ...
//   });
//   const std::int64_t count = split.run_reduce(n, std::int64_t{0}, [&](const LoopSplit::Range& r) {
//     std::int64_t c = 0;
//     for (std::int64_t i = r.lo; i < r.hi; ++i) c += ...;
//     return c;
//   }, std::plus<>{});
//
// (run and run_reduce are the parallel region with begin, end and update; begin, end and update
// are public for loops that need more, and for the tests)
#pragma once
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <tuple>
#include <utility>

namespace cdem {

class LoopSplit {
 public:
  static constexpr int kMaxThreads = 64;
  struct Range {
    std::int64_t lo = 0, hi = 0;
    int thread = 0, threads = 1;
    double t0 = 0;
  };

  // This thread's range of [0, n) (inside the parallel region; every thread calls it).
  Range begin(std::int64_t n) const {
    Range r;
    r.thread = omp_get_thread_num();
    r.threads = omp_get_num_threads();
    std::tie(r.lo, r.hi) = range(r.thread, r.threads, n);
    r.t0 = omp_get_wtime();
    return r;
  }

  // The thread's time for its range (every thread, after its range).
  void end(const Range& r) { record(r.thread, r.threads, omp_get_wtime() - r.t0); }
  // The same with the time given (end, and tests with synthetic times).
  void record(int thread, int threads, double seconds) {
    if (thread >= kMaxThreads) return;
    time_[static_cast<std::size_t>(thread)] = seconds;
    if (thread == 0) seen_ = threads;
  }

  // New cuts from the times of the last run (one thread, after the parallel region).
  void update() {
    const int nt = seen_;
    if (nt < 2 || nt > kMaxThreads) return;
    if (nt != nt_) {  // a new thread count: equal counts first
      nt_ = nt;
      for (int k = 0; k <= nt; ++k) cut_[k] = static_cast<double>(k) / nt;
      return;
    }
    double total = 0;
    for (int k = 0; k < nt; ++k) total += time_[k];
    // (a loop this short is overhead, not work: its times say nothing of its items)
    if (!(total > kMinSeconds * nt)) return;
    // the cost's cumulative sum at each cut, and each cut's target: where the piecewise linear
    // sum reaches k / nt of the total (a thread's range of width 0 keeps it)
    std::array<double, kMaxThreads + 1> target{};  // (1 to nt - 1: cuts 0 and nt stay 0 and 1)
    int seg = 0;
    double before = 0;  // the cost below cut_[seg]
    for (int k = 1; k < nt; ++k) {
      const double want = total * k / nt;
      while (seg < nt - 1 && before + time_[seg] < want) before += time_[seg++];
      const double w = cut_[seg + 1] - cut_[seg];
      const double f = time_[seg] > 0 ? (want - before) / time_[seg] : 0.5;
      target[k] = cut_[seg] + std::clamp(f, 0.0, 1.0) * w;
    }
    // half way there (the times are noisy), keeping every range at least kMinShare of an equal one
    for (int k = 1; k < nt; ++k) {
      double c = 0.5 * (cut_[k] + target[k]);
      const double floor_w = kMinShare / nt;
      c = std::max(c, cut_[k - 1] + floor_w);
      c = std::min(c, 1.0 - (nt - k) * floor_w);
      cut_[k] = c;
    }
  }

  // One parallel region: every thread runs body(its range), then the cuts move.
  template <class Body>
  void run(std::int64_t n, Body&& body) {
#pragma omp parallel
    {
      const Range r = begin(n);
      body(r);
      end(r);
    }
    update();
  }
  // The same for a loop that counts or takes maxima: body(range) returns the thread's value, and
  // the threads' values are folded into init with join. Only for values whose join is exact in
  // any order (integer sums, maxima): the threads fold in the order they finish.
  template <class T, class Body, class Join>
  T run_reduce(std::int64_t n, T init, Body&& body, Join&& join) {
#pragma omp parallel
    {
      const Range r = begin(n);
      const T mine = body(r);
      end(r);
#pragma omp critical(cdem_loop_split_join)
      init = join(init, mine);
    }
    update();
    return init;
  }

  // A count and a maximum (the contacts of a pass and their deepest penetration), for run_reduce.
  struct CountMax {
    std::int64_t count = 0;
    double max = 0;
    std::int64_t at = -1;  // where the maximum is (the body's choice; the least of equal ones)
    static CountMax join(CountMax a, CountMax b) {
      const std::int64_t at = a.max != b.max ? (a.max > b.max ? a.at : b.at)
                              : a.at < 0 ? b.at : b.at < 0 ? a.at : std::min(a.at, b.at);
      return {a.count + b.count, std::max(a.max, b.max), at};
    }
  };

  // Cut k as a fraction of the loop (0 at k = 0; tests, reports).
  double cut(int k) const { return cut_[static_cast<std::size_t>(k)]; }
  // Thread t's range of [0, n) at `threads` threads (begin's, outside a parallel region).
  std::pair<std::int64_t, std::int64_t> range(int t, int threads, std::int64_t n) const {
    const bool mine = threads == nt_ && threads <= kMaxThreads;
    auto at = [&](int k) {
      if (k <= 0) return std::int64_t{0};
      if (k >= threads) return n;
      const double c = mine ? cut_[static_cast<std::size_t>(k)] : static_cast<double>(k) / threads;
      return std::min<std::int64_t>(n, static_cast<std::int64_t>(std::llround(c * static_cast<double>(n))));
    };
    return {at(t), at(t + 1)};
  }

 private:
  static constexpr double kMinSeconds = 20e-6;
  static constexpr double kMinShare = 0.2;
  std::array<double, kMaxThreads + 1> cut_{};
  std::array<double, kMaxThreads> time_{};
  int nt_ = 0, seen_ = 0;
};

}  // namespace cdem
