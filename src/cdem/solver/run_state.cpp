#include "cdem/solver/run_state.hpp"

#include <algorithm>

namespace cdem {

void io_state(StateArchive& ar, Model& m) {
  // nodes
  ar.io("model.x", m.x);
  ar.io("model.v", m.v);
  ar.io("model.f", m.f);
  ar.io("model.mass", m.mass);
  ar.io("model.inv_mass", m.inv_mass);
  ar.io("model.damping", m.damping);
  ar.io("model.local_damping", m.local_damping);
  // blocks
  ar.io("model.block_material", m.block_material);
  ar.io("model.stress", m.stress);
  ar.io("model.stress0", m.stress0);
  ar.io("model.strain_energy", m.strain_energy);
  ar.io("model.vol_ratio", m.vol_ratio);
  // interfaces and spring points
  ar.io("model.iface_normal", m.iface_normal);
  ar.io("model.iface_normal_set", m.iface_normal_set);
  ar.io("model.sp_area", m.sp_area.v);
  ar.io("model.sp_kn", m.sp_kn.v);
  ar.io("model.sp_ks", m.sp_ks.v);
  ar.io("model.sp_fn", m.sp_fn);
  ar.io("model.sp_fs", m.sp_fs);
  ar.io("model.sp_w", m.sp_w);
  ar.io("model.sp_slip", m.sp_slip);
  ar.io("model.sp_dil", m.sp_dil);
  ar.io("model.sp_g0", m.sp_g0);
  ar.io("model.sp_state", m.sp_state);
  ar.io("model.sp_mode", m.sp_mode);
  ar.io("model.sp_break_time", m.sp_break_time);
  ar.io("model.sp_dissipated", m.sp_dissipated);
  ar.io("model.released_points", m.released_points);
  // tied mode: the ties, the clusters, the active interfaces
  ar.io("model.tied", m.tied);
  ar.io("model.sp_tied", m.sp_tied);
  ar.io("model.vtx_nodes", m.vtx_nodes);
  ar.io("model.vtx_run", m.vtx_run);
  ar.io("model.iface_check", m.iface_check);
  ar.io("model.iface_active", m.iface_active);
  ar.io("model.active_ifaces", m.active_ifaces);
  if (ar.loading()) m.active_sorted = 0;  // (older checkpoints kept it in activation order)
  ar.io("model.block_active", m.block_active);
  ar.io("model.tie_reject", m.tie_reject);
}

void io_state(StateArchive& ar, ContactSet& cs) {
  ar.io("contact.enabled", cs.enabled);
  ar.io("contact.skin", cs.skin);
  ar.io("contact.face_iface", cs.face_iface);
  ar.io("contact.kc", cs.kc);
  ar.io("contact.mu", cs.mu);
  ar.io("contact.cand_faces", cs.cand_faces);
  ar.io("contact.cand_nodes", cs.cand_nodes);
  ar.io("contact.x_build", cs.x_build);
  // the half skins of the last build (absent in checkpoints written before fast blocks had larger
  // ones: the set-up's, as then)
  if (!ar.loading() || ar.has("contact.half_skin")) ar.io("contact.half_skin", cs.half_skin);
  // the trigger's other nodes (absent in checkpoints written before each block had its own skin:
  // their list was built on one skin, so it is rebuilt at the next step)
  if (!ar.loading() || ar.has("contact.watch_x")) {
    ar.io("contact.watch_nodes", cs.watch_nodes);
    ar.io("contact.watch_x", cs.watch_x);
    std::uint8_t due = cs.rebuild_due ? 1 : 0;
    ar.io("contact.rebuild_due", due);
    cs.rebuild_due = due != 0;
  } else {
    cs.watch_nodes.clear();
    cs.watch_x.clear();
    cs.rebuild_due = true;
  }
  ar.io("contact.pair_node", cs.pair_node);
  ar.io("contact.pair_block", cs.pair_block);
  ar.io("contact.pair_fn", cs.pair_fn);
  ar.io("contact.pair_ft", cs.pair_ft);
  ar.io("contact.pair_force", cs.pair_force);
  ar.io("contact.pair_kf", cs.pair_kf);
  ar.io("contact.pair_k", cs.pair_k);
  ar.io("contact.pair_diss", cs.pair_diss);
  ar.io("contact.pair_gap", cs.pair_gap);
  ar.io("contact.pair_g0", cs.pair_g0);
  // the nodes' passivity debts (absent in checkpoints written before 7 Dec 2026, whose runs had
  // no such debt: none)
  if (!ar.loading() || ar.has("contact.node_debt")) {
    ar.io("contact.node_debt", cs.node_debt);
  } else {
    std::fill(cs.node_debt.begin(), cs.node_debt.end(), 0.0);
  }
  ar.io("contact.body", cs.body);
  ar.io("contact.on_released", cs.on_released);
  ar.io("contact.face_cand", cs.face_cand);
  ar.io("contact.released_seen", cs.released_seen);
  ar.io("contact.release_drift", cs.release_drift);
  // the release trigger's neighbourhood (absent in checkpoints written before it: every group
  // near until the next build, the old rule; contact_release.cpp)
  if (!ar.loading() || ar.has("contact.blk_near")) {
    ar.io("contact.release_drift_far", cs.release_drift_far);
    ar.io("contact.blk_near", cs.blk_near);
    // (the released counts are the state's, the group boxes this step's: Simulation::io_state
    // recomputes the first and sizes the others, sync_release_counts)
  } else {
    cs.blk_near.clear();
  }
  ar.io("contact.diss_closed", cs.diss_closed);
  ar.io("contact.rebuilds", cs.rebuilds);
  ar.io("contact.active", cs.active);
  ar.io("contact.active_max", cs.active_max);
  ar.io("contact.max_pen_ratio", cs.max_pen_ratio);
  // where it was reached (absent in checkpoints written before 6 Dec 2026: unknown, block -1,
  // until the run's largest penetration grows again)
  if (!ar.loading() || ar.has("contact.max_pen_time")) {
    auto& r = cs.max_pen_at;
    ar.io("contact.max_pen_time", r.time);
    std::vector<std::int32_t> ids{r.node, r.block, r.other};
    ar.io("contact.max_pen_ids", ids);
    ar.io("contact.max_pen_x", r.x);
    if (ar.loading() && ids.size() == 3) r.node = ids[0], r.block = ids[1], r.other = ids[2];
  } else {
    cs.max_pen_at = {};
  }
  // the edge contacts (absent in checkpoints written before they existed: none then)
  if (!ar.loading() || ar.has("contact.ec_a")) {
    ar.io("contact.ec_a", cs.ec_a);
    ar.io("contact.ec_b", cs.ec_b);
    ar.io("contact.ec_key", cs.ec_key);
    ar.io("contact.ec_d0", cs.ec_d0);
    ar.io("contact.ec_gap", cs.ec_gap);
    ar.io("contact.ec_k", cs.ec_k);
    ar.io("contact.ec_diss", cs.ec_diss);
    ar.io("contact.ec_s", cs.ec_s);
    ar.io("contact.ec_t", cs.ec_t);
    ar.io("contact.ec_force", cs.ec_force);
    ar.io("contact.ec_ft", cs.ec_ft);
    ar.io("contact.ec_diss_closed", cs.ec_diss_closed);
    ar.io("contact.ec_active_max", cs.ec_active_max);
  }
  // (the lists derived from the pairs and the step's per-pair geometry, recomputed before it is
  // read, are not stored: index_pairs sizes them after loading, Simulation::io_state)
  // the pair buffers' size (grown at rebuilds only; summary.json reports it)
  std::uint64_t cap = cs.pairs_high;
  ar.io("contact.pair_capacity", cap);
  if (ar.loading()) {
    cs.pairs_high = static_cast<std::size_t>(cap);
    for (auto* v : {&cs.pair_node, &cs.pair_block}) v->reserve(cs.pairs_high);
  }
}

void io_state(StateArchive& ar, GasField& g, const std::string& prefix) {
  ar.io(prefix + ".bodies", g.bodies);
  ar.io(prefix + ".burnt_volume", g.burnt_volume);
  ar.io(prefix + ".cavity", g.cavity);
  ar.io(prefix + ".iface_fill", g.iface_fill);
  ar.io(prefix + ".iface_gas_p", g.iface_gas_p);
  ar.io(prefix + ".iface_body", g.iface_body);
  ar.io(prefix + ".block_body", g.block_body);
  ar.io(prefix + ".block_exterior", g.block_exterior);
}

void io_state(StateArchive& ar, BarCharges& bars) {
  ar.io("bars.seg_p", bars.seg_p);
  ar.io("bars.seg_v", bars.seg_v);
  ar.io("bars.seg_xi", bars.seg_xi);
  ar.io("bars.elem_sigma", bars.elem_sigma);
  ar.io("bars.t_last", bars.t_last);
  io_state(ar, bars.gas, "bars.gas");
}

void io_state(StateArchive& ar, SolidCharges& solids) {
  ar.io("solids.p", solids.p);
  ar.io("solids.lambda", solids.lambda);
  ar.io("solids.v", solids.v);
  ar.io("solids.dead", solids.dead);
  ar.io("solids.t_last", solids.t_last);
  ar.io("solids.dead_count", solids.dead_count);
  io_state(ar, solids.gas, "solids.gas");
}

}  // namespace cdem
