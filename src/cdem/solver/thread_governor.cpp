#include "cdem/solver/thread_governor.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>

namespace cdem {

ThreadGovernor::ThreadGovernor(int max_threads, bool adapt, double period_s, double first_s,
                               double window_s, double margin)
    : max_(std::max(1, max_threads)),
      n_(std::max(1, max_threads)),
      adapt_(adapt && max_threads > 1),
      period_(period_s),
      first_(first_s),
      window_(window_s),
      margin_(margin),
      seconds_at_(static_cast<std::size_t>(std::max(1, max_threads)), 0.0) {}

void ThreadGovernor::set(int n) {
  n_ = n;
  omp_set_num_threads(n);
}

std::string ThreadGovernor::after_step(double step_s) {
  seconds_at_[static_cast<std::size_t>(n_ - 1)] += step_s;
  if (!adapt_) return {};
  switch (phase_) {
    case Phase::Steady:
      steady_s_ += step_s;
      if (steady_s_ >= (probes_ == 0 ? first_ : period_)) {
        phase_ = Phase::ProbeCurrent;
        win_s_ = 0;
        win_steps_ = 0;
      }
      return {};
    case Phase::ProbeCurrent:
    case Phase::ProbeOther: {
      win_s_ += step_s;
      ++win_steps_;
      if (win_s_ < window_ || win_steps_ < 3) return {};
      const double rate = static_cast<double>(win_steps_) / win_s_;
      win_s_ = 0;
      win_steps_ = 0;
      if (phase_ == Phase::ProbeCurrent) {
        // the neighbour to try: one fewer from the top, one more from 1, else alternately
        rate_current_ = rate;
        from_ = n_;
        const int other = n_ == max_ ? n_ - 1 : n_ == 1 ? 2 : (probes_ % 2 ? n_ + 1 : n_ - 1);
        phase_ = Phase::ProbeOther;
        set(other);
        return {};
      }
      ++probes_;
      phase_ = Phase::Steady;
      steady_s_ = 0;
      if (rate > rate_current_ * (1.0 + margin_)) {
        ++switches_;
        return fmt::format("threads {} -> {}: {:.4g} steps/s against {:.4g} with {} ({})", from_,
                           n_, rate, rate_current_, from_,
                           n_ < from_ ? "other work holds a core" : "a core is free again");
      }
      set(from_);
      return {};
    }
  }
  return {};
}

}  // namespace cdem
