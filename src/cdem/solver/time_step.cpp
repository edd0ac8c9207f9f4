#include "cdem/solver/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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
  // Spring stiffness at each node, summed in ascending spring order.
  std::vector<double> k_node(m.n_nodes(), 0.0);
  for (std::size_t sp = 0; sp < m.n_springs(); ++sp) {
    k_node[m.sp_a[sp]] += m.sp_kn[sp];
    k_node[m.sp_b[sp]] += m.sp_kn[sp];
  }
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    const double k = k_node[n];
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
