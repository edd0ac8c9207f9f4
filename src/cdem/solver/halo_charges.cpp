// The bar charges of the halo stage: see halo_charges.hpp.
#include "cdem/solver/halo_charges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "cdem/explosive/gas.hpp"
#include "cdem/parallel/ranks.hpp"

namespace cdem {

HaloBars::HaloBars(BarCharges& bars, const Model& whole, const PartModel& pm, const Model& l,
                   const std::vector<std::int32_t>& part, int rank)
    : bars_(bars), whole_(whole), iface_(pm.iface), own_block_(pm.own) {
  const std::vector<std::int32_t>& block = pm.block;
  if (l.n_blocks() != block.size() || l.n_ifaces() != iface_.size())
    throw std::logic_error("HaloBars: the local model is not the part's");
  own_iface_ = own_interfaces(pm, l, part, rank);
  elem_local_.assign(bars.elem_block.size(), -1);
  for (std::size_t i = 0; i < bars.elem_block.size(); ++i) {
    const auto it = std::lower_bound(block.begin(), block.end(), bars.elem_block[i]);
    if (it == block.end() || *it != bars.elem_block[i]) continue;
    const auto lb = static_cast<std::int32_t>(it - block.begin());
    elem_local_[i] = lb;
    if (own_block_[static_cast<std::size_t>(lb)]) own_elems_.emplace_back(static_cast<std::int32_t>(i), lb);
  }
  for (const auto& b : bars.gas.bodies) cracks_ = cracks_ || b.model == GasModel::Cracks;
  vol_ratio_.assign(whole.n_blocks(), 1.0);
}

std::int32_t HaloBars::local_iface(std::int32_t global) const {
  const auto it = std::lower_bound(iface_.begin(), iface_.end(), global);
  return it != iface_.end() && *it == global ? static_cast<std::int32_t>(it - iface_.begin()) : -1;
}

void HaloBars::load(Model& l, AppliedLoads& out, double t) {
  GasField& g = bars_.gas;
  const int np = l.springs_per_iface;
  // 1. this part's inputs: its bound blocks' volume ratios, its interfaces of the crack list
  mine_.clear();
  mine_.push_back(static_cast<double>(own_elems_.size()));
  for (const auto& [i, lb] : own_elems_) mine_.insert(mine_.end(), {static_cast<double>(i), l.vol_ratio[static_cast<std::size_t>(lb)]});
  const std::size_t count_at = mine_.size();
  mine_.push_back(0.0);
  if (cracks_) {
    std::size_t n = 0;
    const std::size_t nlist = l.tied ? l.active_ifaces.size() : l.n_ifaces();
    for (std::size_t k = 0; k < nlist; ++k) {
      const std::size_t li = l.tied ? static_cast<std::size_t>(l.active_ifaces[k]) : k;
      if (!own_iface_[li]) continue;
      const bool open = crack_open(l, li);
      const double w = open ? crack_aperture(l, li) : 0.0;
      const auto gi = static_cast<std::size_t>(iface_[li]);
      if (!gas_candidate(whole_, g, gi, open, w)) continue;
      mine_.insert(mine_.end(), {static_cast<double>(gi), open ? 1.0 : 0.0, w});
      ++n;
    }
    mine_[count_at] = static_cast<double>(n);
  }
  gather_all(mine_, all_, at_);
  // 2. the whole model's inputs, then every rank steps the charges' state
  order_.clear();
  for (std::size_t r = 0; r + 1 < at_.size(); ++r) {
    const double* p = all_.data() + at_[r];
    const auto ne = static_cast<std::size_t>(*p++);
    for (std::size_t k = 0; k < ne; ++k, p += 2)
      vol_ratio_[static_cast<std::size_t>(bars_.elem_block[static_cast<std::size_t>(p[0])])] = p[1];
    const auto nc = static_cast<std::size_t>(*p++);
    for (std::size_t k = 0; k < nc; ++k, p += 3)
      order_.emplace_back(static_cast<std::int32_t>(p[0]), static_cast<std::int32_t>(p - all_.data()));
  }
  std::sort(order_.begin(), order_.end());  // (each interface once: one owner)
  given_.iface.clear();
  given_.open.clear();
  given_.aperture.clear();
  for (const auto& [gi, at] : order_) {
    given_.iface.push_back(gi);
    given_.open.push_back(all_[static_cast<std::size_t>(at) + 1] != 0 ? 1 : 0);
    given_.aperture.push_back(all_[static_cast<std::size_t>(at) + 2]);
  }
  bar_state(whole_, bars_, vol_ratio_, t, &given_);
  if (g.given_list && g.chain_overflow >= 0)
    throw std::runtime_error(fmt::format(
        "the halo stage: at t = {:.6g} s the gas of a bar filled a crack (interface {}) in the step "
        "its gas reached it, from a block its gas reached in the same step; the halo stage's crack "
        "list does not follow a front that fast. Run with --ranks-mode replicated",
        t, g.chain_overflow));
  // 3. the loads on this part: the gas-filled cracks' faces in the whole list's order (a pair load
  // per spring point), then each bound block inflated by its pressure (single loads per node)
  AppliedLoads::Owned& own = out.owned;
  if (cracks_) {
    for (std::size_t k = 0; k < given_.iface.size(); ++k) {
      const auto gi = static_cast<std::size_t>(given_.iface[k]);
      const std::int32_t d = g.iface_body[gi];
      double p = 0;
      if (d >= 0 && g.bodies[static_cast<std::size_t>(d)].model == GasModel::Cracks && given_.open[k] &&
          given_.aperture[k] > 0)
        p = g.iface_fill[gi] * g.bodies[static_cast<std::size_t>(d)].pressure;
      if (!(p > 0)) p = 0;
      g.iface_gas_p[gi] = static_cast<float>(p);
      if (!(p > 0)) continue;
      const std::int32_t li = local_iface(static_cast<std::int32_t>(gi));
      if (li >= 0) {
        const auto i = static_cast<std::size_t>(li);
        const Vec3 f = (p * l.sp_area.v[i]) * l.iface_normal[i];  // on B's node, along n (A to B)
        for (int q = 0; q < np; ++q) {
          const std::int32_t b = l.sp_b[i * np + q], a = l.sp_a[i * np + q];
          l.f[static_cast<std::size_t>(b)] += f;
          l.f[static_cast<std::size_t>(a)] -= f;
          if (own_iface_[i]) own.add(b, a, f, dot(f, l.v[static_cast<std::size_t>(b)] - l.v[static_cast<std::size_t>(a)]));
        }
      }
    }
  }
  for (std::size_t i = 0; i < bars_.elem_block.size(); ++i) {
    const double sigma = bars_.elem_sigma[i];
    if (!(sigma > 0)) continue;
    const std::int32_t lb = elem_local_[i];
    if (lb >= 0) {
      Vec3 fn[4];
      const int nn = inflation_forces(l, lb, sigma, fn);
      const auto n0 = l.block_first_node[static_cast<std::size_t>(lb)];
      const bool mine = own_block_[static_cast<std::size_t>(lb)] != 0;
      for (int j = 0; j < nn; ++j) {
        l.f[static_cast<std::size_t>(n0 + j)] += fn[j];
        if (mine) own.add(n0 + j, -1, fn[j], dot(fn[j], l.v[static_cast<std::size_t>(n0 + j)]));
      }
      for (int k = 0; k < 3; ++k) l.stress[static_cast<std::size_t>(lb)][k] -= sigma;
    }
  }
}

}  // namespace cdem
