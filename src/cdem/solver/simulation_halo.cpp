// The halo stage of a distributed run in the Simulation (simulation.hpp, parallel/halo.hpp): a
// part's own entities, and the whole model's state gathered from the parts.
//
// A part (make_part) steps its own blocks and its ghost zone. Its kernels give its own entities
// the whole model's bits (tests/verification/test_halo.cpp); the sums a step or a sample forms
// over the model would not: they would run over the part's entities, ghosts included. So a part
// lists only the terms of the entities it owns (own_masks), and its sums, exact (core/
// exact_sum.hpp), are reduced over the ranks: one MPI_Allreduce of the sums' bins, the bits one
// process gets, whatever the parts.
//
// The whole model's Simulation then only holds the state for the run loop's outputs, analyses
// and checkpoints: gather_parts fills it from the parts' own entities when the loop reads all of
// it, gather_sample the few entities a history sample reads.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cdem/parallel/halo.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/physics/tie_failure.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

struct HaloIndex {
  int rank = 0, ranks = 1, np = 0;
  std::vector<std::int32_t> part;  // per global block
  std::vector<std::int32_t> block, node, iface, vertex;  // local -> global (PartModel)
  std::vector<std::uint8_t> own_block, own_node, own_iface, own_vertex;  // per local entity
  std::vector<std::int32_t> vertex_part;  // tied mode: per whole-model vertex, its owner (vertex_owner)
  // own entities' places in the whole's order, ascending: (whole's index, local index), of what
  // gather_parts carries besides the model: the boundary work nodes' v(n-1/2), the load facets'
  // forces
  std::vector<std::pair<std::int32_t, std::int32_t>> work;   // boundary work nodes
  std::vector<std::pair<std::int32_t, std::int32_t>> loads;  // boundary load facets
};

// On the whole model: per rank, its own entities in ascending global order.
struct HaloGatherLists {
  std::vector<std::vector<std::int32_t>> blocks, nodes, ifaces, vertices, work, loads;
  // the gather's scratch buffers, kept between gathers (a sample every few steps: no allocation,
  // no first touch of fresh pages each time; the lists above are what the gather shares)
  mutable std::vector<double> buf, all;
  mutable std::vector<std::int64_t> at;
  mutable std::vector<std::uint8_t> fresh, fresh_w;
};

namespace {

// The part owning each mesh vertex (tied mode): the part of the block of its lowest node. Every
// part owning a block at the vertex holds all its blocks (ring 1, halo.hpp), so the owner's view
// of the vertex's clusters is whole.
std::vector<std::int32_t> vertex_owner(const Model& m, const std::vector<std::int32_t>& part) {
  std::vector<std::int32_t> owner(m.n_vertices(), -1);
  for (std::size_t b = 0; b < m.n_blocks(); ++b)
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
      auto& o = owner[static_cast<std::size_t>(m.node_vertex[n])];
      if (o < 0) o = part[b];  // (nodes ascending: the first seen is the lowest)
    }
  return owner;
}

// Exact conversions to and from double (int32, uint8, float and double all are).
struct Put {
  std::vector<double>& b;
  void operator()(double v) { b.push_back(v); }
  void operator()(const Vec3& v) { b.insert(b.end(), {v.x, v.y, v.z}); }
  void operator()(const Sym6& s) { b.insert(b.end(), s.begin(), s.end()); }
};
struct Get {
  const double* p;
  double d() { return *p++; }
  Vec3 v3() {
    const Vec3 v{p[0], p[1], p[2]};
    p += 3;
    return v;
  }
  Sym6 s6() {
    Sym6 s;
    for (auto& x : s) x = *p++;
    return s;
  }
};

}  // namespace

void Simulation::make_part(const Simulation& whole, const PartModel& pm, const std::vector<std::int32_t>& part) {
  if (!loads_.empty() || contact_.enabled || !rank_blocks_.empty())
    throw std::logic_error("Simulation::make_part: a part takes its charges' load hook after this (HaloCharges), "
                           "and no contact yet");
  auto h = std::make_shared<HaloIndex>();
  h->rank = ranks().rank;
  h->ranks = ranks().size;
  h->np = m_.springs_per_iface;
  h->part = part;
  h->block = pm.block;
  h->node = pm.node;
  h->iface = pm.iface;
  h->vertex = pm.vertex;
  h->own_block = pm.own;
  h->own_node.assign(m_.n_nodes(), 0);
  for (std::size_t b = 0; b < m_.n_blocks(); ++b)
    for (auto n = m_.block_first_node[b]; n < m_.block_first_node[b + 1]; ++n) h->own_node[n] = pm.own[b];
  h->own_iface = own_interfaces(pm, m_, part, h->rank);
  const Model& w = whole.m_;
  if (m_.tied) {
    h->vertex_part = vertex_owner(w, part);
    h->own_vertex.resize(m_.n_vertices());
    for (std::size_t v = 0; v < m_.n_vertices(); ++v)
      h->own_vertex[v] = h->vertex_part[static_cast<std::size_t>(pm.vertex[v])] == h->rank;
    for (auto lv : con_vertices_) {
      const auto gv = pm.vertex[static_cast<std::size_t>(lv)];
      const auto it = std::lower_bound(whole.con_vertices_.begin(), whole.con_vertices_.end(), gv);
      if (it == whole.con_vertices_.end() || *it != gv) throw std::logic_error("make_part: a constrained vertex the whole lacks");
    }
  } else {
    // the springs mode's constraints: the part's are the whole's at its nodes, in the same order
    std::size_t j = 0;
    for (std::size_t g = 0; g < whole.bc_.constraints.size(); ++g) {
      const auto gn = whole.bc_.constraints[g].node;
      const auto it = std::lower_bound(pm.node.begin(), pm.node.end(), gn);
      if (it == pm.node.end() || *it != gn) continue;
      const auto ln = it - pm.node.begin();
      if (j >= bc_.constraints.size() || bc_.constraints[j].node != ln)
        throw std::logic_error("make_part: the part's constraints are not the whole's");
      ++j;
    }
    if (j != bc_.constraints.size()) throw std::logic_error("make_part: the part has constraints the whole lacks");
  }
  // boundary work nodes: the whole's index of each own one
  {
    std::vector<std::int32_t> at(w.n_nodes(), -1);
    for (std::size_t i = 0; i < whole.bc_.work_nodes.size(); ++i) at[static_cast<std::size_t>(whole.bc_.work_nodes[i])] = static_cast<std::int32_t>(i);
    for (std::size_t i = 0; i < bc_.work_nodes.size(); ++i) {
      const auto ln = static_cast<std::size_t>(bc_.work_nodes[i]);
      const auto gw = at[static_cast<std::size_t>(pm.node[ln])];
      if (gw < 0) throw std::logic_error("make_part: a boundary node the whole lacks");
      if (h->own_node[ln]) h->work.emplace_back(gw, static_cast<std::int32_t>(i));
    }
    std::sort(h->work.begin(), h->work.end());
  }
  // load facets: the part's are the whole's of its blocks, in the same order
  {
    std::size_t j = 0;
    for (std::size_t g = 0; g < whole.bc_.loads.size(); ++g) {
      const auto gb = whole.bc_.loads[g].facet.block;
      const auto it = std::lower_bound(pm.block.begin(), pm.block.end(), gb);
      if (it == pm.block.end() || *it != gb) continue;
      const auto lb = it - pm.block.begin();
      if (j >= bc_.loads.size() || bc_.loads[j].facet.block != lb)
        throw std::logic_error("make_part: the part's load facets are not the whole's");
      if (pm.own[static_cast<std::size_t>(lb)]) h->loads.emplace_back(static_cast<std::int32_t>(g), static_cast<std::int32_t>(j));
      ++j;
    }
    if (j != bc_.loads.size()) throw std::logic_error("make_part: the part has load facets the whole lacks");
  }
  halo_ = std::move(h);
  e_initial_ = whole.e_initial_;  // (a part's own set-up summed its part, ghosts included)
}

Simulation::OwnMasks Simulation::own_masks() const {
  if (!halo_) return {};
  const HaloIndex& h = *halo_;
  return {h.own_block.data(), h.own_node.data(), h.own_iface.data(), h.own_vertex.empty() ? nullptr : h.own_vertex.data()};
}

void Simulation::part_inverted(std::int64_t& inv, std::int32_t& first) const {
  // (as step() recounts them: a charge's blocks may collapse, the rock may not)
  const bool any = inv > 0;
  inv = 0;
  first = -1;
  if (!any) return;
  for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
    if (halo_->own_block[b] && rock_inverted(b)) {
      if (first < 0) first = halo_->block[b];
      ++inv;
    }
  }
}

void Simulation::gather_parts(const Simulation& local, const std::vector<double>* extra_local,
                              std::vector<double>* extra_whole) {
  if (!local.halo_) throw std::logic_error("gather_parts: not a part");
  const HaloIndex& h = *local.halo_;
  const Model& l = local.m_;
  const int np = h.np;
  const bool fe = !m_.sp_w.empty(), g0 = !m_.sp_g0.empty();
  if (!gather_) {
    auto g = std::make_shared<HaloGatherLists>();
    const auto n = static_cast<std::size_t>(h.ranks);
    for (auto* v : {&g->blocks, &g->nodes, &g->ifaces, &g->vertices, &g->work, &g->loads}) v->assign(n, {});
    for (std::size_t b = 0; b < m_.n_blocks(); ++b) {
      const auto r = static_cast<std::size_t>(h.part[b]);
      g->blocks[r].push_back(static_cast<std::int32_t>(b));
      for (auto nd = m_.block_first_node[b]; nd < m_.block_first_node[b + 1]; ++nd) g->nodes[r].push_back(nd);
    }
    for (std::size_t i = 0; i < m_.n_ifaces(); ++i)
      g->ifaces[static_cast<std::size_t>(h.part[static_cast<std::size_t>(m_.iface_block_a[i])])].push_back(static_cast<std::int32_t>(i));
    if (m_.tied) {
      const auto& owner = h.vertex_part;
      for (std::size_t v = 0; v < owner.size(); ++v) g->vertices[static_cast<std::size_t>(owner[v])].push_back(static_cast<std::int32_t>(v));
    }
    for (std::size_t i = 0; i < bc_.work_nodes.size(); ++i)
      g->work[static_cast<std::size_t>(h.part[static_cast<std::size_t>(m_.node_block(static_cast<std::size_t>(bc_.work_nodes[i])))])].push_back(static_cast<std::int32_t>(i));
    for (std::size_t i = 0; i < bc_.loads.size(); ++i)
      g->loads[static_cast<std::size_t>(h.part[static_cast<std::size_t>(bc_.loads[i].facet.block)])].push_back(static_cast<std::int32_t>(i));
    gather_ = std::move(g);
  }
  const HaloGatherLists& g = *gather_;
  // This part's own entities, ascending in the whole's order, field by field as unpacked below.
  std::vector<double>& buf = g.buf;
  buf.clear();
  Put put{buf};
  for (std::size_t b = 0; b < l.n_blocks(); ++b) {
    if (!h.own_block[b]) continue;
    put(l.stress[b]);
    put(l.strain_energy[b]);
    put(l.vol_ratio[b]);
    if (!local.ke_.empty()) put(local.ke_[b]);
    if (!local.block_dissipated_.empty()) put(local.block_dissipated_[b]);
    if (!local.cke_.empty()) put(local.cke_[b]);
  }
  for (std::size_t n = 0; n < l.n_nodes(); ++n) {
    if (!h.own_node[n]) continue;
    put(l.x[n]);
    put(l.v[n]);
    put(l.f[n]);
    if (extra_local) put((*extra_local)[n]);
  }
  std::vector<std::uint8_t>& fresh = g.fresh;  // tied: activated in this step (after the list's sorted head)
  if (l.tied) {
    fresh.assign(l.n_ifaces(), 0);
    for (std::size_t k = l.active_sorted; k < l.active_ifaces.size(); ++k) fresh[static_cast<std::size_t>(l.active_ifaces[k])] = 1;
  }
  for (std::size_t i = 0; i < l.n_ifaces(); ++i) {
    if (!h.own_iface[i]) continue;
    put(l.iface_normal[i]);
    if (l.tied) put(l.iface_active[i]), put(l.iface_check[i]), put(fresh[i]);
    for (int q = 0; q < np; ++q) {
      const std::size_t s = i * np + q;
      put(l.sp_fn[s]);
      put(l.sp_fs[s]);
      if (fe) put(l.sp_w[s]), put(l.sp_slip[s]), put(l.sp_dil[s]);
      if (g0) put(l.sp_g0[s]);
      put(l.sp_state[s]);
      put(l.sp_mode[s]);
      put(l.sp_break_time[s]);
      put(l.sp_dissipated[s]);
      if (l.tied) put(l.sp_tied[s]);
    }
  }
  if (l.tied)
    for (std::size_t v = 0; v < l.n_vertices(); ++v) {
      if (!h.own_vertex[v]) continue;
      put(local.vtx_ke_[v]);
      if (!local.vtx_dissipated_.empty()) put(local.vtx_dissipated_[v]);
      if (!local.vtx_cke_.empty()) put(local.vtx_cke_[v]);
      put(local.vtx_reaction_[2 * v]);
      put(local.vtx_reaction_[2 * v + 1]);
      for (auto k = l.vtx_offset[v]; k < l.vtx_offset[v + 1]; ++k) {
        put(static_cast<double>(h.node[static_cast<std::size_t>(l.vtx_nodes[k])]));
        put(l.vtx_run[k]);
      }
    }
  for (const auto& [gw, i] : h.work) put(local.bc_.v_old[static_cast<std::size_t>(i)]);
  for (const auto& [gl, j] : h.loads)
    for (int q = 0; q < 3; ++q) put(local.bc_.load_force[3 * static_cast<std::size_t>(j) + q]);

  std::vector<double>& all = g.all;
  std::vector<std::int64_t>& at = g.at;
  // (to rank 0 alone, which writes the outputs and checkpoints; the other ranks' whole model keeps
  // only what the parts hold alike, below)
  gather_to_root(buf, all, at);
  Model& m = m_;
  // What the parts hold alike (the step's sums were formed over the whole model: step_sums).
  for (auto d : {&Simulation::t_, &Simulation::dt_, &Simulation::w_insert_, &Simulation::w_boundary_,
                 &Simulation::w_absorbed_, &Simulation::w_explosive_, &Simulation::last_boundary_,
                 &Simulation::last_absorbed_, &Simulation::last_explosive_, &Simulation::w_sdamp_,
                 &Simulation::last_sdamp_})
    this->*d = local.*d;
  steps_ = local.steps_;
  inverted_ = local.inverted_;
  first_inverted_ = local.first_inverted_;
  if (h.rank != 0) return;
  std::vector<std::uint8_t>& fresh_w = g.fresh_w;
  fresh_w.assign(m.tied ? m.n_ifaces() : 0, 0);
  for (int r = 0; r < h.ranks; ++r) {
    Get get{all.data() + at[r]};
    const auto rr = static_cast<std::size_t>(r);
    for (auto b : g.blocks[rr]) {
      m.stress[b] = get.s6();
      m.strain_energy[b] = get.d();
      m.vol_ratio[b] = get.d();
      if (!ke_.empty()) ke_[b] = get.d();
      if (!block_dissipated_.empty()) block_dissipated_[b] = get.d();
      if (!cke_.empty()) cke_[b] = get.d();
    }
    for (auto n : g.nodes[rr]) {
      m.x[n] = get.v3();
      m.v[n] = get.v3();
      m.f[n] = get.v3();
      if (extra_whole) (*extra_whole)[n] = get.d();
    }
    for (auto i : g.ifaces[rr]) {
      m.iface_normal[i] = get.v3();
      if (m.tied) {
        m.iface_active[i] = static_cast<std::uint8_t>(get.d());
        m.iface_check[i] = static_cast<std::uint8_t>(get.d());
        fresh_w[i] = static_cast<std::uint8_t>(get.d());
      }
      for (int q = 0; q < np; ++q) {
        const std::size_t s = static_cast<std::size_t>(i) * np + q;
        m.sp_fn[s] = get.d();
        m.sp_fs[s] = get.v3();
        if (fe) m.sp_w[s] = get.d(), m.sp_slip[s] = get.d(), m.sp_dil[s] = get.d();
        if (g0) m.sp_g0[s] = get.d();
        m.sp_state[s] = static_cast<std::uint8_t>(get.d());
        m.sp_mode[s] = static_cast<std::uint8_t>(get.d());
        m.sp_break_time[s] = static_cast<float>(get.d());
        m.sp_dissipated[s] = get.d();
        if (m.tied) m.sp_tied[s] = static_cast<std::uint8_t>(get.d());
      }
    }
    if (m.tied)
      for (auto v : g.vertices[rr]) {
        vtx_ke_[v] = get.d();
        if (!vtx_dissipated_.empty()) vtx_dissipated_[v] = get.d();
        if (!vtx_cke_.empty()) vtx_cke_[v] = get.d();
        vtx_reaction_[2 * static_cast<std::size_t>(v)] = get.d();
        vtx_reaction_[2 * static_cast<std::size_t>(v) + 1] = get.d();
        for (auto k = m.vtx_offset[v]; k < m.vtx_offset[v + 1]; ++k) {
          m.vtx_nodes[k] = static_cast<std::int32_t>(get.d());
          m.vtx_run[k] = static_cast<std::uint8_t>(get.d());
        }
      }
    for (auto i : g.work[rr]) bc_.v_old[static_cast<std::size_t>(i)] = get.v3();
    for (auto i : g.loads[rr])
      for (int q = 0; q < 3; ++q) bc_.load_force[3 * static_cast<std::size_t>(i) + q] = get.v3();
    if (get.p != all.data() + at[r + 1]) throw std::logic_error("gather_parts: the parts' records do not match");
  }
  m.iface_normal_set = l.iface_normal_set;
  m.released_points = 0;
  for (auto st : m.sp_state) m.released_points += st == kReleased;
  if (m.tied) {
    // the active list as one process has it after the step: ascending, then the interfaces
    // activated in the step (tie_failure, in ascending order). A solid charge's collapse in the
    // step activates its interfaces in the load hook, so their order here may differ from one
    // process's (the same set; loading a checkpoint sorts the list again)
    m.active_ifaces.clear();
    for (std::size_t i = 0; i < m.n_ifaces(); ++i)
      if (m.iface_active[i] && !fresh_w[i]) m.active_ifaces.push_back(static_cast<std::int32_t>(i));
    m.active_sorted = m.active_ifaces.size();
    for (std::size_t i = 0; i < m.n_ifaces(); ++i)
      if (fresh_w[i]) m.active_ifaces.push_back(static_cast<std::int32_t>(i));
    std::fill(m.block_active.begin(), m.block_active.end(), 0);
    for (auto i : m.active_ifaces) m.block_active[m.iface_block_a[i]] = m.block_active[m.iface_block_b[i]] = 1;
  }
}

void Simulation::gather_sample(const Simulation& local, const std::vector<std::int32_t>& blocks,
                               const std::vector<std::int32_t>& nodes, const std::vector<std::int32_t>& vertices,
                               bool velocities_only) {
  const HaloIndex& h = *local.halo_;
  const Model& l = local.m_;
  auto local_of = [](const std::vector<std::int32_t>& map, std::int32_t g) {
    const auto it = std::lower_bound(map.begin(), map.end(), g);
    if (it == map.end() || *it != g) throw std::logic_error("gather_sample: an own entity the part lacks");
    return static_cast<std::size_t>(it - map.begin());
  };
  auto block_owner = [&](std::size_t b) { return h.part[b]; };
  auto node_owner = [&](std::int32_t n) { return block_owner(m_.node_block(static_cast<std::size_t>(n))); };
  auto vertex_owner_of = [&](std::int32_t v) { return h.vertex_part[static_cast<std::size_t>(v)]; };
  std::vector<double> buf;
  Put put{buf};
  for (auto b : blocks)
    if (block_owner(static_cast<std::size_t>(b)) == h.rank) put(l.stress[local_of(h.block, b)]);
  for (auto n : nodes) {
    if (node_owner(n) != h.rank) continue;
    const std::size_t ln = local_of(h.node, n);
    put(l.v[ln]);
    if (!velocities_only) put(l.x[ln]), put(l.f[ln]);
  }
  for (auto v : vertices) {
    if (vertex_owner_of(v) != h.rank) continue;
    const std::size_t lv = local_of(h.vertex, v);
    for (auto k = l.vtx_offset[lv]; k < l.vtx_offset[lv + 1]; ++k) {
      put(static_cast<double>(h.node[static_cast<std::size_t>(l.vtx_nodes[k])]));
      put(l.vtx_run[k]);
    }
  }
  std::vector<double> all;
  std::vector<std::int64_t> at;
  gather_to_root(buf, all, at);
  if (h.rank != 0) return;  // (rank 0 alone writes what a sample reads)
  std::vector<Get> from;
  for (int r = 0; r < h.ranks; ++r) from.push_back(Get{all.data() + at[r]});
  for (auto b : blocks) m_.stress[static_cast<std::size_t>(b)] = from[static_cast<std::size_t>(block_owner(static_cast<std::size_t>(b)))].s6();
  for (auto n : nodes) {
    Get& get = from[static_cast<std::size_t>(node_owner(n))];
    const auto gn = static_cast<std::size_t>(n);
    m_.v[gn] = get.v3();
    if (!velocities_only) m_.x[gn] = get.v3(), m_.f[gn] = get.v3();
  }
  for (auto v : vertices) {
    Get& get = from[static_cast<std::size_t>(vertex_owner_of(v))];
    for (auto k = m_.vtx_offset[v]; k < m_.vtx_offset[v + 1]; ++k) {
      m_.vtx_nodes[k] = static_cast<std::int32_t>(get.d());
      m_.vtx_run[k] = static_cast<std::uint8_t>(get.d());
    }
  }
  for (int r = 0; r < h.ranks; ++r)
    if (from[static_cast<std::size_t>(r)].p != all.data() + at[r + 1]) throw std::logic_error("gather_sample: the parts' records do not match");
}

}  // namespace cdem
