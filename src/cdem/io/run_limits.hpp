// The size of a run, checked before it starts (docs/input_safety.md): the number of steps, of
// field outputs and of history samples, against caps a sane run stays far below. Each refusal
// names the keys that set the number; `simulation.allow_large_run = true` lifts the caps, not the
// limits beyond which the numbers overflow (steps past 2^53, field outputs past 1e6).
#pragma once
#include <cstddef>
#include <string>

#include "cdem/io/case.hpp"

namespace cdem {

inline constexpr double kMaxSteps = 1e8;                     // without allow_large_run
inline constexpr double kMaxFieldOutputs = 1e4;              // without allow_large_run
inline constexpr double kMaxHistorySamples = 1e7;            // without allow_large_run
inline constexpr std::size_t kMaxMonitors = 10000;           // without allow_large_run
inline constexpr double kHardMaxSteps = 9007199254740992.0;  // 2^53: t = k dt stays exact
inline constexpr double kHardMaxFieldOutputs = 1e6;

struct RunSize {
  double steps = 0;            // ceil(end_time / dt), or max_steps when smaller
  double field_outputs = 0;    // VTU frames: t = 0, the periodic ones, output_times, the end
  double history_samples = 0;  // rows of the time histories
};

// Field outputs: needs no time step (checked when the case is loaded).
double field_output_count(const Case& c);
void check_field_outputs(const Case& c);

// Everything, once dt is known. `dt_source` says what set dt ("the stable step, limited by the
// springs" or "simulation.dt"). Throws InputError; warns (spdlog) when the whole run is fewer
// than 5 steps (a unit mistake, usually).
RunSize check_run_size(const Case& c, double dt, const std::string& dt_source);

}  // namespace cdem
