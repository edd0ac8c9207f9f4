// The charges of the halo stage: see halo_charges.hpp.
#include "cdem/solver/halo_charges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "cdem/explosive/gas.hpp"
#include "cdem/parallel/ranks.hpp"

namespace cdem {

namespace {

// The gas of a bar or a solid charge filled a crack the given list did not hold (gas.hpp,
// GasField::chain_overflow): the list followed the front one crack too few.
void check_chain(const GasField& g, double t) {
  if (g.given_list && g.chain_overflow >= 0)
    throw std::runtime_error(fmt::format(
        "the halo stage: at t = {:.6g} s the gas of a charge filled a crack (interface {}) in the step "
        "its gas reached it, from a block its gas reached in the same step; the halo stage's crack "
        "list does not follow a front that fast. Run with --ranks-mode replicated",
        t, g.chain_overflow));
}

}  // namespace

HaloCharges::HaloCharges(BarCharges& bars, SolidCharges& solids, const Model& whole, const PartModel& pm,
                         const Model& l, const std::vector<std::int32_t>& part, int rank)
    : bars_(bars), solids_(solids), whole_(whole), iface_(pm.iface), own_block_(pm.own) {
  const std::vector<std::int32_t>& block = pm.block;
  if (l.n_blocks() != block.size() || l.n_ifaces() != iface_.size())
    throw std::logic_error("HaloCharges: the local model is not the part's");
  own_iface_ = own_interfaces(pm, l, part, rank);
  auto bind = [&](const std::vector<std::int32_t>& blocks, const GasField& g, Loaded& at) {
    at.local.assign(blocks.size(), -1);
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const auto it = std::lower_bound(block.begin(), block.end(), blocks[i]);
      if (it == block.end() || *it != blocks[i]) continue;
      const auto lb = static_cast<std::int32_t>(it - block.begin());
      at.local[i] = lb;
      if (own_block_[static_cast<std::size_t>(lb)]) at.own.emplace_back(static_cast<std::int32_t>(i), lb);
    }
    for (const auto& b : g.bodies) at.cracks = at.cracks || b.model == GasModel::Cracks;
  };
  bind(bars.elem_block, bars.gas, bars_at_);
  bind(solids.block, solids.gas, solids_at_);
  vol_ratio_.assign(whole.n_blocks(), 1.0);
}

std::int32_t HaloCharges::local_iface(std::int32_t global) const {
  const auto it = std::lower_bound(iface_.begin(), iface_.end(), global);
  return it != iface_.end() && *it == global ? static_cast<std::int32_t>(it - iface_.begin()) : -1;
}

template <class Value, class Set>
void HaloCharges::gather_inputs(const Model& l, const Loaded& at, const GasField& g, Value value, Set set) {
  // 1. this part's inputs: its loaded blocks' values, its interfaces of the crack list
  mine_.clear();
  mine_.push_back(static_cast<double>(at.own.size()));
  for (const auto& [i, lb] : at.own) mine_.insert(mine_.end(), {static_cast<double>(i), value(lb)});
  const std::size_t count_at = mine_.size();
  mine_.push_back(0.0);
  if (at.cracks) {
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
  // 2. the whole model's inputs: the values, the crack list in the whole model's order
  order_.clear();
  for (std::size_t r = 0; r + 1 < at_.size(); ++r) {
    const double* p = all_.data() + at_[r];
    const auto ne = static_cast<std::size_t>(*p++);
    for (std::size_t k = 0; k < ne; ++k, p += 2) set(static_cast<std::size_t>(p[0]), p[1]);
    const auto nc = static_cast<std::size_t>(*p++);
    for (std::size_t k = 0; k < nc; ++k, p += 3)
      order_.emplace_back(static_cast<std::int32_t>(p[0]), static_cast<std::int32_t>(p - all_.data()));
  }
  std::sort(order_.begin(), order_.end());  // (each interface once: one owner)
  given_.iface.clear();
  given_.open.clear();
  given_.aperture.clear();
  for (const auto& [gi, place] : order_) {
    given_.iface.push_back(gi);
    given_.open.push_back(all_[static_cast<std::size_t>(place) + 1] != 0 ? 1 : 0);
    given_.aperture.push_back(all_[static_cast<std::size_t>(place) + 2]);
  }
}

void HaloCharges::crack_loads(Model& l, GasField& g, AppliedLoads::Owned& own) const {
  // the gas-filled cracks' faces in the whole list's order (a pair load per spring point), as
  // gas_face_loads does over the whole model's list
  const int np = l.springs_per_iface;
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
    if (li < 0) continue;
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

void HaloCharges::inflate(Model& l, std::int32_t lb, double p, AppliedLoads::Owned& own) const {
  Vec3 fn[4];
  const int nn = inflation_forces(l, lb, p, fn);
  const auto n0 = l.block_first_node[static_cast<std::size_t>(lb)];
  const bool mine = own_block_[static_cast<std::size_t>(lb)] != 0;
  for (int j = 0; j < nn; ++j) {
    l.f[static_cast<std::size_t>(n0 + j)] += fn[j];
    if (mine) own.add(n0 + j, -1, fn[j], dot(fn[j], l.v[static_cast<std::size_t>(n0 + j)]));
  }
}

void HaloCharges::load_bars(Model& l, AppliedLoads& out, double t) {
  if (bars_.empty()) return;
  gather_inputs(
      l, bars_at_, bars_.gas, [&l](std::int32_t lb) { return l.vol_ratio[static_cast<std::size_t>(lb)]; },
      [this](std::size_t i, double v) { vol_ratio_[static_cast<std::size_t>(bars_.elem_block[i])] = v; });
  // every rank steps the bars' state; then the loads on this part, as bar_apply's
  bar_state(whole_, bars_, vol_ratio_, t, &given_);
  check_chain(bars_.gas, t);
  if (bars_at_.cracks) crack_loads(l, bars_.gas, out.owned);
  for (std::size_t i = 0; i < bars_.elem_block.size(); ++i) {
    const double sigma = bars_.elem_sigma[i];
    const std::int32_t lb = bars_at_.local[i];
    if (!(sigma > 0) || lb < 0) continue;
    inflate(l, lb, sigma, out.owned);
    for (int k = 0; k < 3; ++k) l.stress[static_cast<std::size_t>(lb)][k] -= sigma;
  }
}

void HaloCharges::load_solids(Model& l, AppliedLoads& out, double t) {
  SolidCharges& sc = solids_;
  if (sc.empty()) return;
  gather_inputs(
      l, solids_at_, sc.gas, [&l](std::int32_t lb) { return current_volume_ratio(l, static_cast<std::size_t>(lb)); },
      [&sc](std::size_t i, double v) { sc.v[i] = v; });
  // every rank steps the solid charges' state (solid_loads' order); then the loads on this part
  solid_gas_inputs(sc, t);
  if (sc.gas.any()) {
    gas_state(whole_, sc.gas, sc.eos, sc.t_last >= 0 ? t - sc.t_last : 0.0, &given_);
    check_chain(sc.gas, t);
    if (solids_at_.cracks) crack_loads(l, sc.gas, out.owned);
  }
  solid_state(whole_, sc, t);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    const std::int32_t lb = solids_at_.local[i];
    if (lb < 0) continue;
    const auto b = static_cast<std::size_t>(lb);
    l.vol_ratio[b] = sc.v[i];
    if (sc.died_now[i]) let_go_of_block(l, lb);
    const double pr = sc.p[i];
    l.stress[b] = {-pr, -pr, -pr, 0, 0, 0};
    if (pr > 0) inflate(l, lb, pr, out.owned);
  }
}

}  // namespace cdem
