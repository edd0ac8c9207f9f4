#include "cdem/parallel/halo.hpp"

#include <algorithm>
#include <stdexcept>

#include "cdem/parallel/partition.hpp"
#include "cdem/parallel/ranks.hpp"

namespace cdem {
namespace {

// v[idx[k]] for each k; an empty array (a state the model does not keep) stays empty.
template <class T>
std::vector<T> take(const std::vector<T>& v, const std::vector<std::int32_t>& idx) {
  std::vector<T> out;
  if (v.empty()) return out;
  out.reserve(idx.size());
  for (auto i : idx) out.push_back(v[static_cast<std::size_t>(i)]);
  return out;
}

// The same for an array of `per` entries per index (the spring points of an interface).
template <class T>
std::vector<T> take(const std::vector<T>& v, const std::vector<std::int32_t>& idx, int per) {
  std::vector<T> out;
  if (v.empty()) return out;
  out.reserve(idx.size() * static_cast<std::size_t>(per));
  for (auto i : idx)
    for (int q = 0; q < per; ++q) out.push_back(v[static_cast<std::size_t>(i) * per + q]);
  return out;
}

}  // namespace

void part_blocks(const Model& m, const std::vector<std::int32_t>& part, std::int32_t p,
                 std::vector<std::int32_t>& blocks, std::vector<std::uint8_t>& own) {
  const std::size_t nb = m.n_blocks();
  if (part.size() != nb) throw std::logic_error("part_blocks: a part per block expected");
  // ring: 0 not in the part's model, 1 own, 2 ghost
  std::vector<std::uint8_t> in(nb, 0);
  for (std::size_t b = 0; b < nb; ++b)
    if (part[b] == p) in[b] = 1;
  // ring 1: the blocks sharing a vertex with an own block
  std::vector<std::int32_t> vstart, vlist;
  vertex_blocks(m.block_first_node, m.node_vertex, vstart, vlist);
  for (std::size_t b = 0; b < nb; ++b) {
    if (part[b] != p) continue;
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
      const auto v = static_cast<std::size_t>(m.node_vertex[n]);
      for (auto k = vstart[v]; k < vstart[v + 1]; ++k) {
        const auto o = static_cast<std::size_t>(vlist[static_cast<std::size_t>(k)]);
        if (!in[o]) in[o] = 2;
      }
    }
  }
  blocks.clear();
  own.clear();
  for (std::size_t b = 0; b < nb; ++b)
    if (in[b]) {
      blocks.push_back(static_cast<std::int32_t>(b));
      own.push_back(in[b] == 1);
    }
}

PartModel cut_part(const Model& m, const std::vector<std::int32_t>& part, std::int32_t p) {
  if (m.tied || !m.vtx_offset.empty())
    throw std::logic_error("cut_part: the model is already set up (tied); cut it before");
  PartModel out;
  part_blocks(m, part, p, out.block, out.own);
  const std::size_t nb = out.block.size();
  for (auto o : out.own) (o ? out.own_blocks : out.ghost_blocks) += 1;
  Model& l = out.model;
  l.dim = m.dim;
  l.springs_per_iface = m.springs_per_iface;

  // ---- blocks and their nodes ----
  std::vector<std::int32_t> local_block(m.n_blocks(), -1);
  for (std::size_t k = 0; k < nb; ++k) local_block[static_cast<std::size_t>(out.block[k])] = static_cast<std::int32_t>(k);
  l.block_first_node.assign(nb + 1, 0);
  l.geom_offset.assign(nb + 1, 0);
  for (std::size_t k = 0; k < nb; ++k) {
    const auto b = static_cast<std::size_t>(out.block[k]);
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
      if (!out.own[k]) out.ghost_nodes.push_back(static_cast<std::int32_t>(out.node.size()));
      out.node.push_back(n);
    }
    l.block_first_node[k + 1] = static_cast<std::int32_t>(out.node.size());
    for (auto g = m.geom_offset[b]; g < m.geom_offset[b + 1]; ++g) l.geom.push_back(m.geom[static_cast<std::size_t>(g)]);
    l.geom_offset[k + 1] = static_cast<std::int32_t>(l.geom.size());
  }
  // the groups: each global group's blocks are a contiguous run of the local order
  for (const auto& g : m.groups) {
    const auto lo = std::lower_bound(out.block.begin(), out.block.end(), g.begin) - out.block.begin();
    const auto hi = std::lower_bound(out.block.begin(), out.block.end(), g.end) - out.block.begin();
    if (hi > lo) l.groups.push_back({g.type, g.kind, static_cast<std::int32_t>(lo), static_cast<std::int32_t>(hi)});
  }
  l.block_type = take(m.block_type, out.block);
  l.block_region = take(m.block_region, out.block);
  l.block_material = take(m.block_material, out.block);
  l.block_elem_tag = take(m.block_elem_tag, out.block);
  l.block_volume0 = take(m.block_volume0, out.block);
  l.block_size = take(m.block_size, out.block);
  l.block_altitude0 = take(m.block_altitude0, out.block);
  l.stress = take(m.stress, out.block);
  l.stress0 = take(m.stress0, out.block);
  l.strain_energy = take(m.strain_energy, out.block);
  l.vol_ratio = take(m.vol_ratio, out.block);
  l.no_contact = take(m.no_contact, out.block);

  // ---- nodes and mesh vertices ----
  std::vector<std::int32_t> local_node(m.n_nodes(), -1);
  for (std::size_t k = 0; k < out.node.size(); ++k) local_node[static_cast<std::size_t>(out.node[k])] = static_cast<std::int32_t>(k);
  for (auto n : out.node) out.vertex.push_back(m.node_vertex[static_cast<std::size_t>(n)]);
  std::sort(out.vertex.begin(), out.vertex.end());
  out.vertex.erase(std::unique(out.vertex.begin(), out.vertex.end()), out.vertex.end());
  l.vertex_X = take(m.vertex_X, out.vertex);
  l.node_vertex.reserve(out.node.size());
  for (auto n : out.node) {
    const auto v = m.node_vertex[static_cast<std::size_t>(n)];
    l.node_vertex.push_back(static_cast<std::int32_t>(std::lower_bound(out.vertex.begin(), out.vertex.end(), v) - out.vertex.begin()));
  }
  l.x = take(m.x, out.node);
  l.v = take(m.v, out.node);
  l.f = take(m.f, out.node);
  l.mass = take(m.mass, out.node);
  l.inv_mass = take(m.inv_mass, out.node);
  l.damping = take(m.damping, out.node);
  l.local_damping = take(m.local_damping, out.node);

  // ---- interfaces between two local blocks, and their spring points ----
  for (std::size_t i = 0; i < m.n_ifaces(); ++i)
    if (local_block[static_cast<std::size_t>(m.iface_block_a[i])] >= 0 && local_block[static_cast<std::size_t>(m.iface_block_b[i])] >= 0)
      out.iface.push_back(static_cast<std::int32_t>(i));
  const int np = m.springs_per_iface;
  for (auto i : out.iface) {
    l.iface_block_a.push_back(local_block[static_cast<std::size_t>(m.iface_block_a[static_cast<std::size_t>(i)])]);
    l.iface_block_b.push_back(local_block[static_cast<std::size_t>(m.iface_block_b[static_cast<std::size_t>(i)])]);
    for (int q = 0; q < np; ++q) {
      const auto s = static_cast<std::size_t>(i) * np + q;
      l.sp_a.push_back(local_node[static_cast<std::size_t>(m.sp_a[s])]);
      l.sp_b.push_back(local_node[static_cast<std::size_t>(m.sp_b[s])]);
    }
  }
  l.iface_material = take(m.iface_material, out.iface);
  l.iface_normal = take(m.iface_normal, out.iface);
  l.iface_normal_set = m.iface_normal_set;
  for (auto [dst, src] : {std::pair{&l.sp_area, &m.sp_area}, std::pair{&l.sp_kn, &m.sp_kn}, std::pair{&l.sp_ks, &m.sp_ks}}) {
    dst->per = src->per;
    dst->v = take(src->v, out.iface);
  }
  l.sp_fn = take(m.sp_fn, out.iface, np);
  l.sp_fs = take(m.sp_fs, out.iface, np);
  l.sp_w = take(m.sp_w, out.iface, np);
  l.sp_slip = take(m.sp_slip, out.iface, np);
  l.sp_dil = take(m.sp_dil, out.iface, np);
  l.sp_g0 = take(m.sp_g0, out.iface, np);
  l.sp_state = take(m.sp_state, out.iface, np);
  l.sp_mode = take(m.sp_mode, out.iface, np);
  l.sp_break_time = take(m.sp_break_time, out.iface, np);
  l.sp_dissipated = take(m.sp_dissipated, out.iface, np);
  l.released_points = 0;
  for (auto st : l.sp_state) l.released_points += st == kReleased;
  // block -> interfaces, each block's list ascending (as the global one: the same relative order)
  l.block_iface_offset.assign(nb + 1, 0);
  for (std::size_t i = 0; i < out.iface.size(); ++i) {
    ++l.block_iface_offset[static_cast<std::size_t>(l.iface_block_a[i]) + 1];
    ++l.block_iface_offset[static_cast<std::size_t>(l.iface_block_b[i]) + 1];
  }
  for (std::size_t k = 0; k < nb; ++k) l.block_iface_offset[k + 1] += l.block_iface_offset[k];
  l.block_iface_list.assign(static_cast<std::size_t>(l.block_iface_offset[nb]), 0);
  {
    std::vector<std::int32_t> fill(l.block_iface_offset.begin(), l.block_iface_offset.end() - 1);
    for (std::size_t i = 0; i < out.iface.size(); ++i) {
      const auto code = static_cast<std::int32_t>(i) + 1;
      l.block_iface_list[static_cast<std::size_t>(fill[static_cast<std::size_t>(l.iface_block_a[i])]++)] = code;
      l.block_iface_list[static_cast<std::size_t>(fill[static_cast<std::size_t>(l.iface_block_b[i])]++)] = -code;
    }
  }

  // ---- materials, regions, settings ----
  l.block_materials = m.block_materials;
  l.iface_materials = m.iface_materials;
  l.spring_laws = m.spring_laws;
  l.mat_lambda = m.mat_lambda;
  l.mat_shear = m.mat_shear;
  l.mat_beta = m.mat_beta;
  l.release_distance_factor = m.release_distance_factor;
  l.release_cos = m.release_cos;
  l.tie_reject = m.tie_reject;
  l.region_names = m.region_names;

  // ---- boundary facets of local blocks ----
  for (const auto& set : m.facet_sets) {
    Model::FacetSet ls;
    ls.name = set.name;
    for (const auto& f : set.facets) {
      const auto b = local_block[static_cast<std::size_t>(f.block)];
      if (b < 0) continue;
      Model::BoundaryFacet lf;
      lf.block = b;
      for (int q = 0; q < f.count(); ++q) lf.nodes[static_cast<std::size_t>(q)] = local_node[static_cast<std::size_t>(f.nodes[static_cast<std::size_t>(q)])];
      ls.facets.push_back(lf);
    }
    l.facet_sets.push_back(std::move(ls));
  }
  return out;
}

HaloExchange::HaloExchange(const PartModel& pm, const std::vector<std::int32_t>& part) {
  const int n = ranks().size;
  const Model& l = pm.model;
  // per owner, the global nodes this part holds as ghosts (ascending: the local order)
  std::vector<std::vector<std::int32_t>> ask(static_cast<std::size_t>(n)), asked;
  std::vector<std::vector<std::int32_t>> mine(static_cast<std::size_t>(n));
  for (std::size_t lb = 0; lb < pm.block.size(); ++lb) {
    if (pm.own[lb]) continue;
    const auto q = part[static_cast<std::size_t>(pm.block[lb])];
    if (q < 0 || q >= n) throw std::logic_error("HaloExchange: a part per rank expected");
    for (auto ln = l.block_first_node[lb]; ln < l.block_first_node[lb + 1]; ++ln) {
      ask[static_cast<std::size_t>(q)].push_back(pm.node[static_cast<std::size_t>(ln)]);
      mine[static_cast<std::size_t>(q)].push_back(ln);
    }
  }
  all_to_all(ask, asked);
  for (int q = 0; q < n; ++q) {
    if (ask[q].empty() && asked[q].empty()) continue;
    peers_.push_back(q);
    recv_.push_back(std::move(mine[static_cast<std::size_t>(q)]));
    std::vector<std::int32_t> send;
    for (auto g : asked[static_cast<std::size_t>(q)]) {
      const auto it = std::lower_bound(pm.node.begin(), pm.node.end(), g);
      if (it == pm.node.end() || *it != g) throw std::logic_error("HaloExchange: asked for a node this part does not hold");
      send.push_back(static_cast<std::int32_t>(it - pm.node.begin()));
    }
    send_.push_back(std::move(send));
  }
  for (std::size_t k = 0; k < peers_.size(); ++k) {
    sbuf_.emplace_back(6 * send_[k].size());
    rbuf_.emplace_back(6 * recv_[k].size());
  }
}

std::size_t HaloExchange::nodes_sent() const {
  std::size_t c = 0;
  for (const auto& s : send_) c += s.size();
  return c;
}
std::size_t HaloExchange::nodes_received() const {
  std::size_t c = 0;
  for (const auto& r : recv_) c += r.size();
  return c;
}

void HaloExchange::exchange(Model& local) {
  for (std::size_t k = 0; k < peers_.size(); ++k) {
    double* b = sbuf_[k].data();
    for (auto ln : send_[k]) {
      const Vec3 &x = local.x[static_cast<std::size_t>(ln)], &v = local.v[static_cast<std::size_t>(ln)];
      *b++ = x.x, *b++ = x.y, *b++ = x.z, *b++ = v.x, *b++ = v.y, *b++ = v.z;
    }
  }
  exchange_with(peers_, sbuf_, rbuf_);
  for (std::size_t k = 0; k < peers_.size(); ++k) {
    const double* b = rbuf_[k].data();
    for (auto ln : recv_[k]) {
      Vec3 &x = local.x[static_cast<std::size_t>(ln)], &v = local.v[static_cast<std::size_t>(ln)];
      x = {b[0], b[1], b[2]};
      v = {b[3], b[4], b[5]};
      b += 6;
    }
  }
}

std::vector<std::uint8_t> own_interfaces(const PartModel& pm, const Model& local, const std::vector<std::int32_t>& part,
                                         std::int32_t p) {
  std::vector<std::uint8_t> own(local.n_ifaces());
  for (std::size_t i = 0; i < local.n_ifaces(); ++i)
    own[i] = part[static_cast<std::size_t>(pm.block[static_cast<std::size_t>(local.iface_block_a[i])])] == p;
  return own;
}

std::vector<std::int32_t> node_spring_counts(const Model& whole, const PartModel& pm) {
  std::vector<std::int32_t> all(whole.n_nodes(), 0);
  for (std::size_t s = 0; s < whole.n_springs(); ++s) {
    ++all[static_cast<std::size_t>(whole.sp_a[s])];
    ++all[static_cast<std::size_t>(whole.sp_b[s])];
  }
  std::vector<std::int32_t> out;
  out.reserve(pm.node.size());
  for (auto n : pm.node) out.push_back(all[static_cast<std::size_t>(n)]);
  return out;
}

}  // namespace cdem
