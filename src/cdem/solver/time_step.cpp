#include "cdem/solver/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cdem {

StableStep stable_time_step(const Model& m, double safety) {
  StableStep s;
  s.dt_block = std::numeric_limits<double>::infinity();
  s.dt_spring = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    const auto& mat = m.block_materials[m.block_material[b]];
    if (!mat.explosive.empty()) continue;  // explosive blocks: limited by their EOS (issue 3)
    const auto k = m.block_material[b];
    const double cp = std::sqrt((m.mat_lambda[k] + 2.0 * m.mat_shear[k]) / mat.density);
    const double d = m.block_altitude0[b] / cp;
    if (d < s.dt_block) {
      s.dt_block = d;
      s.block = static_cast<std::int64_t>(b);
    }
  }
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    double k = 0;
    for (auto q = m.node_sp_offset[n]; q < m.node_sp_offset[n + 1]; ++q) {
      const auto e = m.node_sp_list[q];
      k += m.sp_kn[(e > 0 ? e : -e) - 1];
    }
    if (k <= 0) continue;
    const double d = std::sqrt(2.0 * m.mass[n] / k);
    if (d < s.dt_spring) {
      s.dt_spring = d;
      s.node = static_cast<std::int64_t>(n);
    }
  }
  s.limit = s.dt_spring < s.dt_block ? "springs" : "blocks";
  s.dt = safety * std::min(s.dt_block, s.dt_spring);
  s.safety = safety;
  return s;
}

}  // namespace cdem
