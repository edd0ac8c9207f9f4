#include "cdem/parallel/partition.hpp"

#include "cdem/explosive/charges.hpp"
#include "cdem/mesh/topology.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#ifdef CDEM_HAVE_METIS
#include <metis.h>
#endif

namespace cdem {
namespace {

// Heavy edge between blocks bound to one charge: 1000 interfaces' worth.
constexpr std::int32_t kTogetherWeight = 1000;

// CSR from an edge list (both directions added), duplicates kept (there are none: one interface
// per face).
void fill_csr(BlockGraph& g, std::size_t n, const std::vector<std::array<std::int32_t, 3>>& edges) {
  g.xadj.assign(n + 1, 0);
  for (const auto& e : edges) ++g.xadj[e[0] + 1], ++g.xadj[e[1] + 1];
  for (std::size_t i = 0; i < n; ++i) g.xadj[i + 1] += g.xadj[i];
  g.adjncy.assign(g.xadj[n], 0);
  g.adjwgt.assign(g.xadj[n], 0);
  std::vector<std::int32_t> pos(g.xadj.begin(), g.xadj.end() - 1);
  for (const auto& e : edges) {
    g.adjncy[pos[e[0]]] = e[1], g.adjwgt[pos[e[0]]++] = e[2];
    g.adjncy[pos[e[1]]] = e[0], g.adjwgt[pos[e[1]]++] = e[2];
  }
}

}  // namespace

void vertex_blocks(const std::vector<std::int32_t>& offset, const std::vector<std::int32_t>& vertices,
                   std::vector<std::int32_t>& start, std::vector<std::int32_t>& list) {
  std::int32_t nv = 0;
  for (auto v : vertices) nv = std::max(nv, v + 1);
  start.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (auto v : vertices) ++start[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 0; v < static_cast<std::size_t>(nv); ++v) start[v + 1] += start[v];
  list.assign(vertices.size(), 0);
  std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t b = 0; b + 1 < offset.size(); ++b)  // (blocks ascending: each vertex's list is too)
    for (auto k = offset[b]; k < offset[b + 1]; ++k)
      list[static_cast<std::size_t>(fill[static_cast<std::size_t>(vertices[static_cast<std::size_t>(k)])]++)] =
          static_cast<std::int32_t>(b);
}

std::int32_t block_weight(ElemType type, int interfaces) {
  const int kernel = type == ElemType::Tet4 ? 10 : type == ElemType::Quad4 ? 8 : 4;
  return kernel + interfaces;
}

std::vector<std::int64_t> block_ranges(const BlockGraph& g, int parts) {
  if (parts < 1) throw std::invalid_argument("block_ranges: parts must be at least 1");
  const std::int64_t n = static_cast<std::int64_t>(g.n());
  std::vector<std::int64_t> prefix(n + 1, 0);  // weight of blocks [0, b)
  for (std::int64_t b = 0; b < n; ++b) prefix[b + 1] = prefix[b] + g.vwgt[b];
  std::vector<std::int64_t> first(parts + 1, 0);
  first[parts] = n;
  for (int r = 1; r < parts; ++r) {
    // The cut nearest to r / parts of the total weight, never before the previous one. Exact
    // integer arithmetic, the same on every machine: weights of ~15 per block times 2^20 parts
    // stay below 2^63 up to 10^11 blocks.
    const std::int64_t target = prefix[n] * r;
    auto it = std::lower_bound(prefix.begin(), prefix.end(), target,
                               [&](std::int64_t w, std::int64_t t) { return w * parts < t; });
    std::int64_t b = it - prefix.begin();
    if (b > 0 && b <= n && target - prefix[b - 1] * parts < prefix[b] * parts - target) --b;
    first[r] = std::clamp<std::int64_t>(b, first[r - 1], n);
  }
  return first;
}

std::vector<std::int32_t> ranges_to_parts(const std::vector<std::int64_t>& first) {
  std::vector<std::int32_t> part(first.empty() ? 0 : first.back());
  for (std::size_t r = 0; r + 1 < first.size(); ++r)
    std::fill(part.begin() + first[r], part.begin() + first[r + 1], static_cast<std::int32_t>(r));
  return part;
}

BlockGraph block_graph(const Model& m, const std::vector<std::int32_t>& together) {
  BlockGraph g;
  const std::size_t n = m.n_blocks();
  g.points_per_iface = m.springs_per_iface;
  std::vector<std::array<std::int32_t, 3>> edges;
  edges.reserve(m.n_ifaces());
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    const auto a = m.iface_block_a[i], b = m.iface_block_b[i];
    const bool tie = !together.empty() && together[a] >= 0 && together[a] == together[b];
    edges.push_back({a, b, tie ? kTogetherWeight : static_cast<std::int32_t>(m.springs_per_iface)});
  }
  fill_csr(g, n, edges);
  g.vwgt.resize(n);
  for (std::size_t b = 0; b < n; ++b) g.vwgt[b] = block_weight(m.block_type[b], g.xadj[b + 1] - g.xadj[b]);
  g.bv_offset.assign(m.block_first_node.begin(), m.block_first_node.end());
  g.bv.assign(m.node_vertex.begin(), m.node_vertex.end());
  return g;
}

BlockGraph mesh_block_graph(const Mesh& mesh) {
  BlockGraph g;
  const std::size_t n = mesh.num_elements();
  g.points_per_iface = mesh.dim == 3 ? 3 : 2;
  std::vector<std::int32_t> identity(n);
  std::iota(identity.begin(), identity.end(), 0);
  std::vector<FaceRec> faces = sorted_faces(mesh, identity);
  std::vector<std::array<std::int32_t, 3>> edges;
  edges.reserve(faces.size() / 2);
  for (std::size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].key == faces[i + 1].key) {
      edges.push_back({faces[i].block, faces[i + 1].block, g.points_per_iface});
      ++i;
    }
  std::vector<FaceRec>().swap(faces);
  fill_csr(g, n, edges);
  g.vwgt.resize(n);
  for (std::size_t e = 0; e < n; ++e) g.vwgt[e] = block_weight(mesh.elem_type[e], g.xadj[e + 1] - g.xadj[e]);
  if (4 * n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::length_error("mesh_block_graph: more than 2^31 block vertices");
  g.bv_offset.assign(n + 1, 0);
  for (std::size_t e = 0; e < n; ++e) g.bv_offset[e + 1] = g.bv_offset[e] + nodes_of(mesh.elem_type[e]);
  g.bv.resize(static_cast<std::size_t>(g.bv_offset[n]));
  for (std::size_t e = 0; e < n; ++e)
    for (int k = 0; k < nodes_of(mesh.elem_type[e]); ++k)
      g.bv[static_cast<std::size_t>(g.bv_offset[e] + k)] = mesh.elem_vertices[e][static_cast<std::size_t>(k)];
  return g;
}

std::vector<std::int32_t> charge_groups(std::size_t n_blocks, const BarCharges& bars,
                                        const SolidCharges& solids) {
  std::vector<std::int32_t> g(n_blocks, -1);
  for (std::size_t i = 0; i < bars.elem_block.size(); ++i)
    if (bars.elem_bar_offset[i] < bars.elem_bar_offset[i + 1])
      g[bars.elem_block[i]] = bars.elem_bar[bars.elem_bar_offset[i]];
  const auto nb = static_cast<std::int32_t>(bars.bars.size());
  for (std::size_t k = 0; k < solids.block.size(); ++k) g[solids.block[k]] = nb + solids.charge[k];
  return g;
}

bool have_metis() {
#ifdef CDEM_HAVE_METIS
  return true;
#else
  return false;
#endif
}

std::vector<std::int32_t> partition_kway(const BlockGraph& g, int parts, double ufactor) {
  std::vector<std::int32_t> part(g.n(), 0);
  if (parts <= 1 || g.n() == 0) return part;
#ifdef CDEM_HAVE_METIS
  static_assert(sizeof(idx_t) == sizeof(std::int32_t), "METIS built with 32-bit indices expected");
  idx_t nv = static_cast<idx_t>(g.n()), ncon = 1, np = parts, objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_OBJTYPE] = METIS_OBJTYPE_CUT;
  options[METIS_OPTION_UFACTOR] = static_cast<idx_t>(std::lround((ufactor - 1.0) * 1000));
  options[METIS_OPTION_SEED] = 1;
  options[METIS_OPTION_NUMBERING] = 0;
  // METIS takes non-const pointers; it does not write the graph.
  auto* xadj = const_cast<idx_t*>(g.xadj.data());
  auto* adjncy = const_cast<idx_t*>(g.adjncy.data());
  auto* vwgt = const_cast<idx_t*>(g.vwgt.data());
  auto* adjwgt = const_cast<idx_t*>(g.adjwgt.data());
  const int rc = METIS_PartGraphKway(&nv, &ncon, xadj, adjncy, vwgt, nullptr, adjwgt, &np, nullptr,
                                     nullptr, options, &objval, part.data());
  if (rc != METIS_OK)
    throw std::runtime_error("METIS_PartGraphKway failed (code " + std::to_string(rc) + ")");
  return part;
#else
  (void)ufactor;
  throw std::runtime_error("this cdemblast was built without METIS (install libmetis-dev, rebuild)");
#endif
}

namespace {

// (part, block) as one sortable key
std::uint64_t key_of(std::int32_t p, std::int32_t b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(p)) << 32) | static_cast<std::uint32_t>(b);
}
std::int32_t key_part(std::uint64_t k) { return static_cast<std::int32_t>(k >> 32); }
std::int32_t key_block(std::uint64_t k) { return static_cast<std::int32_t>(k & 0xffffffffu); }

void sort_unique(std::vector<std::uint64_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// Every part's ghost zone as the halo stage builds it (halo.cpp, part_blocks), all parts at once:
// the (part, ghost block) keys, sorted: the blocks of other parts at a vertex that a part touches.
std::vector<std::uint64_t> halo_ghosts(const BlockGraph& g, const std::vector<std::int32_t>& part) {
  std::vector<std::int32_t> start, list;
  vertex_blocks(g.bv_offset, g.bv, start, list);
  const std::size_t nv = start.size() - 1;
  std::vector<std::uint64_t> ring1;
  std::vector<std::int32_t> at;  // the parts at a vertex
  for (std::size_t v = 0; v < nv; ++v) {
    at.clear();
    for (auto k = start[v]; k < start[v + 1]; ++k) {
      const auto p = part[static_cast<std::size_t>(list[static_cast<std::size_t>(k)])];
      if (std::find(at.begin(), at.end(), p) == at.end()) at.push_back(p);
    }
    if (at.size() < 2) continue;
    for (auto k = start[v]; k < start[v + 1]; ++k) {
      const auto b = list[static_cast<std::size_t>(k)];
      for (auto p : at)
        if (p != part[static_cast<std::size_t>(b)]) ring1.push_back(key_of(p, b));
    }
  }
  std::vector<std::int32_t>().swap(start);
  std::vector<std::int32_t>().swap(list);
  sort_unique(ring1);
  return ring1;
}

}  // namespace

PartitionQuality partition_quality(const BlockGraph& g, const std::vector<std::int32_t>& part, int parts,
                                   const std::vector<std::int32_t>& together) {
  PartitionQuality q;
  q.parts = parts;
  const std::size_t n = g.n();
  std::vector<double> weight(parts, 0.0), stepped(parts, 0.0), bytes(parts, 0.0);
  std::vector<std::int64_t> blocks(parts, 0), ghosts(parts, 0);
  std::int64_t edges = 0;
  double wsum = 0;
  for (std::size_t b = 0; b < n; ++b) {
    const int p = part[b];
    const double w = g.vwgt.empty() ? 1.0 : g.vwgt[b];
    weight[p] += w;
    wsum += w;
    ++blocks[p];
    for (auto k = g.xadj[b]; k < g.xadj[b + 1]; ++k) {
      const auto o = static_cast<std::size_t>(g.adjncy[k]);
      if (o <= b) continue;
      ++edges;
      if (part[o] != p) ++q.edge_cut;
    }
  }
  stepped = weight;
  std::vector<std::uint64_t> peers;  // (part, neighbour), both ways
  if (parts > 1) {
    if (g.bv_offset.size() != n + 1) throw std::invalid_argument("partition_quality: the graph has no block vertices");
    for (const auto k : halo_ghosts(g, part)) {
      const auto p = key_part(k), b = key_block(k);
      const auto owner = part[static_cast<std::size_t>(b)];
      ++ghosts[p];
      stepped[p] += g.vwgt.empty() ? 1.0 : g.vwgt[b];
      // x and v of each of its nodes (a node per vertex): received by p, sent by its owner
      const double state = 6.0 * 8 * static_cast<double>(g.bv_offset[b + 1] - g.bv_offset[b]);
      bytes[p] += state;
      bytes[owner] += state;
      peers.push_back(key_of(p, owner));
      peers.push_back(key_of(owner, p));
    }
    sort_unique(peers);
  }
  const double wmean = wsum / parts;
  q.imbalance = wmean > 0 ? *std::max_element(weight.begin(), weight.end()) / wmean : 1.0;
  q.edge_cut_share = edges > 0 ? static_cast<double>(q.edge_cut) / edges : 0.0;
  q.blocks_min = *std::min_element(blocks.begin(), blocks.end());
  q.blocks_max = *std::max_element(blocks.begin(), blocks.end());
  std::vector<int> neighbours(parts, 0);
  for (auto k : peers) ++neighbours[key_part(k)];
  double stepped_sum = 0;
  for (int p = 0; p < parts; ++p) {
    q.ghosts_max = std::max(q.ghosts_max, ghosts[p]);
    q.ghosts_mean += static_cast<double>(ghosts[p]) / parts;
    q.stepped_max = std::max(q.stepped_max, stepped[p]);
    stepped_sum += stepped[p];
    q.neighbours_max = std::max(q.neighbours_max, neighbours[p]);
    q.neighbours_mean += static_cast<double>(neighbours[p]) / parts;
    q.bytes_max = std::max(q.bytes_max, bytes[p]);
    q.bytes_mean += bytes[p] / parts;
    q.messages_max = std::max(q.messages_max, 2.0 * neighbours[p]);  // one Isend + one Irecv each
  }
  q.stepped_share = wsum > 0 ? stepped_sum / wsum : 1.0;
  if (!together.empty()) {
    std::vector<std::int32_t> first_part;
    std::vector<std::uint8_t> split;
    for (std::size_t b = 0; b < n; ++b) {
      const auto t = together[b];
      if (t < 0) continue;
      if (static_cast<std::size_t>(t) >= first_part.size()) first_part.resize(t + 1, -1), split.resize(t + 1, 0);
      if (first_part[t] < 0) first_part[t] = part[b];
      else if (first_part[t] != part[b]) split[t] = 1;
    }
    for (auto s : split) q.together_split += s;
  }
  return q;
}

Projection project(const BlockGraph& g, const PartitionQuality& q, double seconds_per_unit,
                   const Network& net, const StepSums& sums) {
  Projection pr;
  double total = 0;
  for (std::size_t b = 0; b < g.n(); ++b) total += g.vwgt.empty() ? 1.0 : g.vwgt[b];
  const double add_s = (q.parts > 1 ? sums.terms_max : sums.terms) * sums.seconds_per_term;
  const double stages = q.parts > 1 ? std::ceil(std::log2(static_cast<double>(q.parts))) : 0.0;
  const double reduce_s = q.parts > 1 ? stages * (2 * net.latency + sums.reduce_bytes / net.bandwidth) : 0.0;
  pr.sums_s = add_s + reduce_s;
  pr.compute_s = q.stepped_max * seconds_per_unit + add_s;
  pr.comm_s = q.messages_max * net.latency + q.bytes_max / net.bandwidth + reduce_s;
  pr.ratio = pr.comm_s > 0 ? pr.compute_s / pr.comm_s : 0.0;
  const double ideal = (total * seconds_per_unit + sums.terms * sums.seconds_per_term) / q.parts;
  pr.efficiency = ideal / (pr.compute_s + pr.comm_s);
  return pr;
}

}  // namespace cdem
