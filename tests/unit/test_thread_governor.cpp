// The thread governor of a run (solver/thread_governor.hpp), driven with synthetic step times:
// it keeps its threads while they are faster, drops one when a probe finds the step faster with
// fewer (another process holds a core), climbs back when the cores are free again, ignores
// differences within its margin, and does nothing when fixed or with one thread.
#include <gtest/gtest.h>
#include <omp.h>

#include "cdem/solver/thread_governor.hpp"

namespace cdem {
namespace {

// Steps `seconds` of wall time in steps of the time `step_of(threads)` takes; returns the
// messages the governor gave.
template <class F>
int drive(ThreadGovernor& g, double seconds, F step_of) {
  int messages = 0;
  for (double t = 0; t < seconds;) {
    const double s = step_of(g.threads());
    t += s;
    messages += !g.after_step(s).empty();
  }
  return messages;
}

struct ThreadsRestored {
  int saved = omp_get_max_threads();
  ~ThreadsRestored() { omp_set_num_threads(saved); }
};

TEST(ThreadGovernor, KeepsThreadsThatAreFaster) {
  ThreadsRestored restore;
  ThreadGovernor g(2, true, 1.0, 0.5, 0.05, 0.1);
  // 2 threads 1.8x faster than 1: every probe of 1 thread loses
  EXPECT_EQ(drive(g, 10.0, [](int n) { return n == 2 ? 1e-3 : 1.8e-3; }), 0);
  EXPECT_EQ(g.threads(), 2);
  EXPECT_EQ(g.switches(), 0);
  // time was spent at 1 thread only in the probe windows: ~0.05 s per 1 s
  EXPECT_GT(g.seconds_at()[0], 0.0);
  EXPECT_LT(g.seconds_at()[0], 0.1 * g.seconds_at()[1]);
}

TEST(ThreadGovernor, DropsAThreadOnABusyMachineAndClimbsBack) {
  ThreadsRestored restore;
  ThreadGovernor g(2, true, 1.0, 0.5, 0.05, 0.1);
  // another process holds a core: 2 threads take 3x as long as 1 (barriers wait for the thread
  // that is off its core)
  auto busy = [](int n) { return n == 2 ? 3e-3 : 1e-3; };
  EXPECT_EQ(drive(g, 2.0, busy), 1);
  EXPECT_EQ(g.threads(), 1);
  EXPECT_EQ(omp_get_max_threads(), 1);  // applied to the next parallel regions
  EXPECT_EQ(drive(g, 5.0, busy), 0);    // probes of 2 threads keep losing
  EXPECT_EQ(g.threads(), 1);
  // the other process ends
  EXPECT_EQ(drive(g, 3.0, [](int n) { return n == 2 ? 0.55e-3 : 1e-3; }), 1);
  EXPECT_EQ(g.threads(), 2);
  EXPECT_EQ(omp_get_max_threads(), 2);
  EXPECT_EQ(g.switches(), 2);
}

TEST(ThreadGovernor, ProbesBothNeighboursInTheMiddle) {
  ThreadsRestored restore;
  ThreadGovernor g(4, true, 1.0, 0.5, 0.05, 0.1);
  // 3 threads are the best (one core busy): from 4 it steps down to 3 and stays there while the
  // probes of 2 and of 4 both lose
  auto step = [](int n) { return n == 3 ? 1e-3 : n == 4 ? 2.5e-3 : n == 2 ? 1.4e-3 : 2.6e-3; };
  drive(g, 20.0, step);
  EXPECT_EQ(g.threads(), 3);
  EXPECT_EQ(g.switches(), 1);
  EXPECT_GT(g.seconds_at()[1], 0.0);  // 2 threads were probed
  EXPECT_GT(g.seconds_at()[3], 0.0);  // and 4
}

TEST(ThreadGovernor, DifferencesWithinTheMarginAreNoise) {
  ThreadsRestored restore;
  ThreadGovernor g(2, true, 1.0, 0.5, 0.05, 0.1);
  EXPECT_EQ(drive(g, 10.0, [](int n) { return n == 2 ? 1e-3 : 0.95e-3; }),
            0);  // 1 thread 5 % faster
  EXPECT_EQ(g.threads(), 2);
}

TEST(ThreadGovernor, FixedOrSingleThreadNeverChanges) {
  ThreadsRestored restore;
  ThreadGovernor fixed(2, false, 1.0, 0.5, 0.05, 0.1);
  EXPECT_EQ(drive(fixed, 5.0, [](int n) { return n == 2 ? 3e-3 : 1e-3; }), 0);
  EXPECT_EQ(fixed.threads(), 2);
  EXPECT_EQ(fixed.seconds_at()[0], 0.0);
  ThreadGovernor one(1, true, 1.0, 0.5, 0.05, 0.1);
  EXPECT_EQ(drive(one, 5.0, [](int) { return 1e-3; }), 0);
  EXPECT_EQ(one.threads(), 1);
}

}  // namespace
}  // namespace cdem
