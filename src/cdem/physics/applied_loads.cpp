#include "cdem/physics/applied_loads.hpp"

#include <omp.h>

namespace cdem {

void AppliedLoads::now_terms(const Model& m) {
  // Each load's term formed in parallel (the velocities were just written by every thread: read
  // by one serial loop they cost twice as much at 2 threads as at 1).
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
}

}  // namespace cdem
