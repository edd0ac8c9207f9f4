// The thread count of a run on a machine it may share (docs/performance.md, "Threads on a
// shared machine").
//
// A step is a sequence of parallel loops, each ending at a barrier. When another process holds
// one of the cores, the operating system time-slices one of the run's threads against it; every
// barrier then waits for the thread that is off its core, for up to a scheduler slice (ms), and
// two threads run slower than one: measured on the 3D multi-hole bar case (9 000 blocks) with one
// busy process beside it, 2 threads took 3.1x as long per step as 1. No wait policy helps: a
// spinning thread burns the core the other process needs, a sleeping one adds a wake-up per
// barrier.
//
// Since results are bitwise the same for any thread count (the project's contract), the count can
// change at any step. The governor times the steps (not the outputs) and now and then probes:
// it runs a short window at the current count and one at a neighbouring count (one fewer, or one
// more up to the maximum) and keeps the faster, with a margin against noise. So a run keeps its
// threads on a quiet machine, drops to the cores it really gets when the machine is shared, and
// climbs back when the other work ends. It costs the probe windows at the slower count: at most
// window / period of the run (1.5 % with the defaults) when the probed count is twice as slow.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cdem {

class ThreadGovernor {
 public:
  // max_threads: the run's threads (the count it starts at); adapt = false keeps it fixed.
  // period_s: wall time stepping between probes (the first one after first_s); window_s: wall
  // time of each of the two windows of a probe; margin: how much faster (relative) the other
  // count must be to be taken.
  ThreadGovernor(int max_threads, bool adapt, double period_s = 20.0, double first_s = 2.0,
                 double window_s = 0.3, double margin = 0.1);

  // After each step, with the wall time the step took (s). May call omp_set_num_threads; returns
  // a message when it changed the count ("" otherwise).
  std::string after_step(double step_s);

  int threads() const { return n_; }
  int max_threads() const { return max_; }
  std::int64_t switches() const { return switches_; }
  // wall time spent stepping at each thread count (index: count - 1)
  const std::vector<double>& seconds_at() const { return seconds_at_; }

 private:
  enum class Phase { Steady, ProbeCurrent, ProbeOther };
  void set(int n);
  int max_, n_;
  bool adapt_;
  double period_, first_, window_, margin_;
  Phase phase_ = Phase::Steady;
  double steady_s_ = 0, win_s_ = 0, rate_current_ = 0;
  std::int64_t win_steps_ = 0, switches_ = 0, probes_ = 0;
  int from_ = 0;  // the count the probe started at
  std::vector<double> seconds_at_;
};

}  // namespace cdem
