#include "cdem/analysis/uplift.hpp"

#include "cdem/analysis/monitors.hpp"
#include "cdem/core/loop_split.hpp"

namespace cdem {

Vec3 up_direction(const Model& m, Vec3 up) {
  return norm(up) > 0 ? normalized(up) : (m.dim == 2 ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
}

UpliftTracker::UpliftTracker(const Model& m, Vec3 up, std::size_t monitors)
    : up_(up), max_up_(m.n_nodes(), 0.0), mon_max_(monitors, 0.0), mon_time_(monitors, 0.0) {}

void UpliftTracker::update(const Model& m) {
  const auto nn = static_cast<std::int64_t>(m.n_nodes());
  const Vec3 up = up_;
  double* mx = max_up_.data();
  static LoopSplit split;
  split.run(nn, [&](const LoopSplit::Range& part) {
    for (std::int64_t n = part.lo; n < part.hi; ++n) {
      const double u = dot(m.x[n] - m.X(static_cast<std::size_t>(n)), up);
      if (u > mx[n]) mx[n] = u;
    }
  });
}

UpliftTracker::Peak UpliftTracker::peak(const Model& m, bool rock_only) const {
  Peak p;
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    if (rock_only && !(m.block_materials[m.block_material[b]].rock_fraction() > 0)) continue;
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n)
      if (max_up_[n] > p.value) p.value = max_up_[n], p.where = m.X(n);
  }
  return p;
}

void UpliftTracker::sample_monitors(const Model& m, const std::vector<std::int32_t>& blocks, double t) {
  for (std::size_t k = 0; k < blocks.size() && k < mon_max_.size(); ++k) {
    const double u = dot(sample_block(m, blocks[k]).displacement, up_);
    if (u > mon_max_[k]) mon_max_[k] = u, mon_time_[k] = t;
  }
}

}  // namespace cdem
