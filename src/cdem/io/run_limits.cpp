#include "cdem/io/run_limits.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "cdem/core/error.hpp"

namespace cdem {
namespace {

const char* kLift = "set simulation.allow_large_run = true if the run is meant";

}  // namespace

double field_output_count(const Case& c) {
  double n = 2 + static_cast<double>(c.output_times.size());  // t = 0, the end, the listed times
  if (c.output_interval > 0) n += std::ceil(c.end_time / c.output_interval);
  return n;
}

void check_field_outputs(const Case& c) {
  const double n = field_output_count(c);
  const double cap = c.allow_large_run ? kHardMaxFieldOutputs : kMaxFieldOutputs;
  if (!(n <= cap))
    throw InputError(fmt::format(
        "{}: key 'simulation.output_interval': {:g} s over end_time = {:g} s gives {:.3g} field "
        "outputs (a VTU file of the whole model each), more than the {:.0e} allowed{}",
        c.path, c.output_interval, c.end_time, n, cap,
        c.allow_large_run ? "" : fmt::format("; use a larger interval, or {}", kLift)));
}

RunSize check_run_size(const Case& c, double dt, const std::string& dt_source) {
  RunSize r;
  const double steps = std::ceil(c.end_time / dt - 1e-9);
  const std::string dt_text = fmt::format("dt = {:.4g} s ({})", dt, dt_source);
  // The keys that set the count: end_time, and dt when the case fixes it.
  const std::string keys = c.fixed_dt > 0 ? "keys 'simulation.end_time' and 'simulation.dt'"
                                          : "key 'simulation.end_time'";
  // Overflow first: a step count that is not a number the run loop can count exactly.
  if (!(steps <= kHardMaxSteps) && !(c.max_steps > 0))
    throw InputError(
        fmt::format("{}: {}: end_time = {:g} s with {} is {:.3g} steps, more than a "
                    "run can count (2^53); check end_time and dt",
                    c.path, keys, c.end_time, dt_text, steps));
  r.steps =
      std::max(1.0, c.max_steps > 0 ? std::min(steps, static_cast<double>(c.max_steps)) : steps);
  if (r.steps > kMaxSteps && !c.allow_large_run)
    throw InputError(fmt::format(
        "{}: {}: end_time = {:g} s with {} is {:.3g} steps, more than the {:.0e} a run may take; "
        "shorten end_time, coarsen the mesh, cap it with simulation.max_steps, or {}",
        c.path, keys, c.end_time, dt_text, r.steps, kMaxSteps, kLift));
  if (r.steps > kHardMaxSteps)
    throw InputError(
        fmt::format("{}: key 'simulation.max_steps': {} steps are more than a run "
                    "can count (2^53)",
                    c.path, c.max_steps));
  // History rows: every history_interval, at most every step (0: every step).
  r.history_samples = c.history_interval > 0
                          ? std::min(r.steps, std::ceil(c.end_time / c.history_interval) + 1)
                          : r.steps;
  if (r.history_samples > kMaxHistorySamples && !c.allow_large_run)
    throw InputError(fmt::format(
        "{}: key 'simulation.history_interval': {:g} s (0: every step) gives {:.3g} samples of "
        "the time histories over {:.3g} steps, more than the {:.0e} allowed; use a larger "
        "interval, or {}",
        c.path, c.history_interval, r.history_samples, r.steps, kMaxHistorySamples, kLift));
  r.field_outputs = field_output_count(c);
  check_field_outputs(c);
  if (c.end_time > 0 && steps < 5 && !(c.max_steps > 0))
    spdlog::warn(
        "{}: the whole run is {:.0f} step(s): end_time = {:g} s with {}; are the times "
        "in seconds and the mesh in metres?",
        c.path, steps, c.end_time, dt_text);
  return r;
}

}  // namespace cdem
