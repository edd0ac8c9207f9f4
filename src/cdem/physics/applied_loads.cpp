#include "cdem/physics/applied_loads.hpp"

#include <omp.h>

namespace cdem {

double AppliedLoads::power_now(const Model& m) {
  // Each load's term formed in parallel (the velocities were just written by every thread: read
  // by one serial loop they cost twice as much at 2 threads as at 1), then summed serially in the
  // record's order: the same sum, bit for bit, for any thread count.
  const auto nn = static_cast<std::int64_t>(node.size());
  const auto nall = nn + static_cast<std::int64_t>(pair_b.size());
  terms.resize(static_cast<std::size_t>(nall));  // (grows only)
#pragma omp parallel for schedule(static) if (nall > 4096)
  for (std::int64_t i = 0; i < nall; ++i) {
    if (i < nn) {
      terms[i] = dot(force[i], m.v[node[i]]);
    } else {
      const auto j = static_cast<std::size_t>(i - nn);
      terms[i] = dot(pair_force[j], m.v[pair_b[j]] - m.v[pair_a[j]]);
    }
  }
  double p = 0;
  for (std::int64_t i = 0; i < nall; ++i) p += terms[i];
  return p;
}

}  // namespace cdem
