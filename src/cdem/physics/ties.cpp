#include "cdem/physics/ties.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "cdem/mesh/element_geometry.hpp"

namespace cdem {
namespace {

// The unit normal of interface i from A to B at the current positions: the mean of the two
// faces' area vectors (as the spring kernel).
Vec3 current_normal(const Model& m, std::int32_t i) {
  const int np = m.springs_per_iface;
  Vec3 pa[3], pb[3];
  for (int q = 0; q < np; ++q) {
    pa[q] = m.x[m.sp_a[static_cast<std::size_t>(i) * np + q]];
    pb[q] = m.x[m.sp_b[static_cast<std::size_t>(i) * np + q]];
  }
  return normalized(face_area_vector(std::span<const Vec3>(pa, np), np) +
                    face_area_vector(std::span<const Vec3>(pb, np), np));
}

bool breakable(const Model& m, std::int32_t i) {
  return m.spring_laws[m.iface_material[i]].law != InterfaceLaw::Elastic;
}

void update_check_flag(Model& m, std::int32_t i) {
  const int np = m.springs_per_iface;
  bool any = false;
  for (int q = 0; q < np; ++q) any = any || m.sp_tied[static_cast<std::size_t>(i) * np + q];
  m.iface_check[i] = any && breakable(m, i);
}

}  // namespace

void build_ties(Model& m) {
  m.tied = true;
  const std::size_t ns = m.n_springs(), nn = m.n_nodes(), ni = m.n_ifaces(), nb = m.n_blocks();
  const int np = m.springs_per_iface;
  m.sp_tied.assign(ns, 0);
  for (std::size_t s = 0; s < ns; ++s) {
    m.sp_tied[s] = m.sp_state[s] == kIntact;
    if (m.sp_tied[s]) {  // no spring force while tied (a springs-mode preload is dropped)
      m.sp_fn[s] = 0;
      m.sp_fs[s] = {};
    }
  }
  if (m.sp_g0.empty()) m.sp_g0.assign(ns, 0.0);
  // the quick reject of tie_failure: ||sigma||_F below min(f_t, c / (1 + tan phi)) breaks no tie
  m.tie_reject.assign(m.spring_laws.size(), 0.0);
  for (std::size_t k = 0; k < m.spring_laws.size(); ++k) {
    const SpringLaw& l = m.spring_laws[k];
    m.tie_reject[k] = l.law == InterfaceLaw::Elastic ? 1e300 : std::min(l.ft, l.c / (1.0 + l.tan_phi));
  }
  for (std::size_t s = 0; s < ns; ++s)
    if (m.sp_tied[s]) m.sp_g0[s] = 0;
  // vertex -> nodes, ascending
  std::int32_t nv = 0;
  for (auto v : m.node_vertex) nv = std::max(nv, v + 1);
  m.vtx_offset.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (auto v : m.node_vertex) ++m.vtx_offset[v + 1];
  std::int32_t kmax = 0;
  for (std::int32_t v = 0; v < nv; ++v) {
    kmax = std::max(kmax, m.vtx_offset[v + 1]);
    m.vtx_offset[v + 1] += m.vtx_offset[v];
  }
  m.vtx_nodes.assign(nn, -1);
  {
    std::vector<std::int32_t> fill(m.vtx_offset.begin(), m.vtx_offset.end() - 1);
    for (std::size_t n = 0; n < nn; ++n) m.vtx_nodes[fill[m.node_vertex[n]]++] = static_cast<std::int32_t>(n);
  }
  m.vtx_run.assign(nn, 0);
  // one slot per thread (untie_at_vertex runs in parallel over vertices: tie_failure.cpp)
  m.vtx_scratch_slot = 4 * static_cast<std::size_t>(kmax) + 2;
  m.vtx_scratch.assign(m.vtx_scratch_slot * kMaxUntieThreads, 0);
  for (std::int32_t v = 0; v < nv; ++v) split_vertex(m, v);
  // interfaces
  m.iface_check.assign(ni, 0);
  m.iface_active.assign(ni, 0);
  m.active_ifaces.clear();
  m.active_ifaces.reserve(ni);
  m.active_merge.clear();
  m.active_merge.reserve(ni);
  m.block_active.assign(nb, 0);
  for (std::size_t i = 0; i < ni; ++i) {
    const auto ii = static_cast<std::int32_t>(i);
    update_check_flag(m, ii);
    bool open = false;
    for (int q = 0; q < np; ++q) {
      const std::size_t s = i * np + q;
      open = open || (!m.sp_tied[s] && m.sp_state[s] != kReleased);
    }
    if (open) activate_interface(m, ii);
  }
  m.active_sorted = m.active_ifaces.size();  // (activated in ascending order)
  // One motion per cluster: the mass-weighted mean velocity (momentum kept), the first node's
  // position (the nodes of a vertex start coincident).
  for (std::int32_t v = 0; v < nv; ++v) {
    const auto o0 = m.vtx_offset[v], o1 = m.vtx_offset[v + 1];
    for (auto p = o0; p < o1;) {
      auto q = p + 1;
      while (q < o1 && !m.vtx_run[q]) ++q;
      double mass = 0;
      Vec3 mom{};
      for (auto k = p; k < q; ++k) {
        const auto n = m.vtx_nodes[k];
        mass += m.mass[n];
        mom += m.mass[n] * m.v[n];
      }
      const Vec3 vc = mass > 0 ? mom / mass : m.v[m.vtx_nodes[p]];
      const Vec3 xc = m.x[m.vtx_nodes[p]];
      for (auto k = p; k < q; ++k) {
        m.v[m.vtx_nodes[k]] = vc;
        m.x[m.vtx_nodes[k]] = xc;
      }
      p = q;
    }
  }
}

void split_vertex(Model& m, std::int32_t v) {
  const auto o0 = m.vtx_offset[v], o1 = m.vtx_offset[v + 1];
  const int k = o1 - o0;
  if (k <= 0) return;
  const int np = m.springs_per_iface;
  std::int32_t* node = m.vtx_scratch.data();        // the vertex's nodes, ascending
  std::int32_t* parent = node + k;                  // union-find over local indices
  std::int32_t* label = parent + k;                 // smallest local index of the cluster
  std::int32_t* out = label + k;
  std::copy(m.vtx_nodes.begin() + o0, m.vtx_nodes.begin() + o1, node);
  std::sort(node, node + k);
  for (int j = 0; j < k; ++j) parent[j] = j;
  auto local = [&](std::int32_t n) {
    return static_cast<std::int32_t>(std::lower_bound(node, node + k, n) - node);
  };
  auto find = [&](std::int32_t j) {
    while (parent[j] != j) j = parent[j] = parent[parent[j]];
    return j;
  };
  for (int j = 0; j < k; ++j) {
    const std::int32_t n = node[j];
    const std::int32_t b = m.node_block(static_cast<std::size_t>(n));
    for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
      const std::int32_t code = m.block_iface_list[e];
      const bool a_side = code > 0;
      const std::size_t s0 = static_cast<std::size_t>(block_iface_index(code)) * np;
      for (int q = 0; q < np; ++q) {
        const std::size_t s = s0 + q;
        if (!m.sp_tied[s]) continue;
        const std::int32_t mine = a_side ? m.sp_a[s] : m.sp_b[s];
        if (mine != n) continue;
        const std::int32_t other = a_side ? m.sp_b[s] : m.sp_a[s];
        const std::int32_t lo = local(other);
        if (lo >= k || node[lo] != other) continue;  // (not a node of this vertex: never)
        const std::int32_t ra = find(j), rb = find(lo);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
  }
  // The root of each set is its smallest local index (unions keep the smaller root).
  for (int j = 0; j < k; ++j) label[j] = find(j);
  int w = 0;
  for (int j = 0; j < k; ++j) {
    if (label[j] != j) continue;
    m.vtx_run[o0 + w] = 1;
    for (int j2 = j; j2 < k; ++j2)
      if (label[j2] == j) {
        if (j2 != j) m.vtx_run[o0 + w] = 0;
        out[w++] = node[j2];
      }
  }
  std::copy(out, out + k, m.vtx_nodes.begin() + o0);
}

void activate_interface(Model& m, std::int32_t i) {
  if (m.iface_active[i]) return;
  m.iface_active[i] = 1;
  m.active_ifaces.push_back(i);  // within the capacity reserved at set-up: no allocation
  m.block_active[m.iface_block_a[i]] = 1;
  m.block_active[m.iface_block_b[i]] = 1;
  m.iface_normal[i] = current_normal(m, i);
}

void order_active_ifaces(Model& m) {
  auto& a = m.active_ifaces;
  const std::size_t n = a.size(), head = std::min(m.active_sorted, n);
  if (head == n) return;
  std::sort(a.begin() + static_cast<std::ptrdiff_t>(head), a.end());
  if (head > 0) {
    m.active_merge.resize(n);  // within its capacity: no allocation
    std::merge(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(head),
               a.begin() + static_cast<std::ptrdiff_t>(head), a.end(), m.active_merge.begin());
    a.swap(m.active_merge);
  }
  m.active_sorted = n;
}

namespace {

// Whether nodes a (of block block_a) and b, split from one mesh vertex, are still joined through
// the tied spring points at that vertex: a breadth-first search over the nodes of a's cluster,
// stopping at b. Returns 0 when b is reached, else the number of nodes of a's component, which
// are left at the start of the scratch slot (for split_cluster).
// Each step goes from a node to the other node of a tied point at it, through the interfaces of
// the node's block, and knows that node's block from the interface's other side (no search of
// block_first_node). Work space: one slot of vtx_scratch (set-up-sized, 4 x the largest vertex
// degree; the nodes reached are at most the vertex's).
std::size_t component_without(Model& m, std::int32_t a, std::int32_t block_a, std::int32_t b,
                              std::int32_t* scratch) {
  const int np = m.springs_per_iface;
  std::int32_t* node = scratch;                                  // nodes reached, in order
  std::int32_t* block = node + m.vtx_scratch_slot / 2;           // their blocks
  std::size_t n_reached = 1, head = 0;
  node[0] = a;
  block[0] = block_a;
  while (head < n_reached) {
    const std::int32_t n = node[head], blk = block[head];
    ++head;
    for (auto e = m.block_iface_offset[blk]; e < m.block_iface_offset[blk + 1]; ++e) {
      const std::int32_t code = m.block_iface_list[e];
      const bool a_side = code > 0;
      const std::int32_t j = block_iface_index(code);
      const std::size_t s0 = static_cast<std::size_t>(j) * np;
      for (int q = 0; q < np; ++q) {
        const std::size_t s = s0 + q;
        // (the node first: the points of this interface at other vertices may be another
        // thread's, being untied now; tie_failure.cpp)
        if ((a_side ? m.sp_a[s] : m.sp_b[s]) != n || !m.sp_tied[s]) continue;
        const std::int32_t other = a_side ? m.sp_b[s] : m.sp_a[s];
        if (other == b) return 0;
        if (std::find(node, node + n_reached, other) != node + n_reached) continue;
        node[n_reached] = other;
        block[n_reached] = a_side ? m.iface_block_b[j] : m.iface_block_a[j];
        ++n_reached;
      }
    }
  }
  return n_reached;
}

// Splits the cluster of vertex v that holds a into a's component (the n_a nodes at the start of
// scratch slot, left there by component_without) and the rest, keeping split_vertex's canonical
// order: clusters by their smallest node, nodes ascending in each. The part holding the cluster's
// first node keeps its place; the other moves to its place among the later clusters.
void split_cluster(Model& m, std::int32_t v, std::int32_t a, std::size_t n_a, std::int32_t* scratch) {
  const auto o0 = m.vtx_offset[v], o1 = m.vtx_offset[v + 1];
  const std::size_t half = m.vtx_scratch_slot / 2;
  std::int32_t* comp = scratch;                             // a's component (sorted below)
  std::int32_t* out = comp + half;                          // the vertex's list from the cluster on
  std::int32_t* run = out + half / 2;                       // and its run marks
  std::sort(comp, comp + n_a);
  auto p = o0;
  while (p < o1 && m.vtx_nodes[p] != a) ++p;
  if (p == o1 || !m.vtx_run[o0]) {  // (a state not made here, e.g. a damaged checkpoint's)
    split_vertex(m, v);
    return;
  }
  while (!m.vtx_run[p]) --p;                                // the cluster's first node
  auto q = p + 1;
  while (q < o1 && !m.vtx_run[q]) ++q;
  // The cluster's nodes (ascending) in two parts, in one pass: X holds its first node and takes
  // the cluster's place; Y (listed after the component in the scratch) goes among the later
  // clusters, before the first whose first node is larger.
  const bool first_in_a = std::binary_search(comp, comp + n_a, m.vtx_nodes[p]);
  std::int32_t* y = comp + n_a;
  int w = 0, ny = 0;
  for (auto k = p; k < q; ++k) {
    if (std::binary_search(comp, comp + n_a, m.vtx_nodes[k]) == first_in_a) {
      run[w] = w == 0;
      out[w++] = m.vtx_nodes[k];
    } else {
      y[ny++] = m.vtx_nodes[k];
    }
  }
  if (ny == 0) return;  // (b not in a's cluster: a state not made here; nothing to split)
  auto k = q;
  for (; k < o1 && !(m.vtx_run[k] && m.vtx_nodes[k] > y[0]); ++k) run[w] = m.vtx_run[k], out[w++] = m.vtx_nodes[k];
  for (int j = 0; j < ny; ++j) run[w] = j == 0, out[w++] = y[j];
  for (; k < o1; ++k) run[w] = m.vtx_run[k], out[w++] = m.vtx_nodes[k];
  for (int j = 0; j < w; ++j) {
    m.vtx_nodes[p + j] = out[j];
    m.vtx_run[p + j] = static_cast<std::uint8_t>(run[j]);
  }
}

}  // namespace

void untie_at_vertex(Model& m, std::size_t s, int slot) {
  if (!m.sp_tied[s]) return;
  m.sp_tied[s] = 0;
  const auto i = static_cast<std::int32_t>(s / static_cast<std::size_t>(m.springs_per_iface));
  // The clusters change only if a and b are no longer joined through other tied points (around
  // the edges of the vertex's ball of blocks there usually is such a path, a few blocks long).
  // If they are not, their cluster is split in two: a's component, which the search has just
  // walked whole, and the rest (removing one link from a connected set leaves at most two). The
  // clusters are a function of the tied points alone, in split_vertex's canonical order, so
  // this is the same state as recomputing the vertex (test TiedClusters.UntieMatchesFullSplit),
  // whatever the order in which a vertex's points are untied, one at a time.
  std::int32_t* scratch = m.vtx_scratch.data() + static_cast<std::size_t>(slot) * m.vtx_scratch_slot;
  const std::int32_t a = m.sp_a[s];
  const std::size_t n_a = component_without(m, a, m.iface_block_a[i], m.sp_b[s], scratch);
  if (n_a > 0) split_cluster(m, m.node_vertex[a], a, n_a, scratch);
}

void after_untie(Model& m, std::int32_t i) {
  activate_interface(m, i);
  update_check_flag(m, i);
}

void untie_point(Model& m, std::size_t s) {
  if (!m.sp_tied[s]) return;
  untie_at_vertex(m, s, 0);
  after_untie(m, static_cast<std::int32_t>(s / static_cast<std::size_t>(m.springs_per_iface)));
}

std::size_t count_clusters(const Model& m) {
  std::size_t n = 0;
  for (auto r : m.vtx_run) n += r;
  return n;
}

OpenedStiffness set_opened_stiffness(Model& m, double eta, double omega2_max,
                                     const std::vector<std::int32_t>* counts) {
  const int np = m.springs_per_iface;
  std::vector<std::int32_t> count(m.n_nodes(), 0);
  if (counts) {
    if (counts->size() != m.n_nodes()) throw std::logic_error("set_opened_stiffness: a count per node expected");
    count = *counts;
  } else {
    for (std::size_t s = 0; s < m.n_springs(); ++s) {
      ++count[m.sp_a[s]];
      ++count[m.sp_b[s]];
    }
  }
  std::vector<double> ratio;
  ratio.reserve(m.n_ifaces());
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    double k = std::numeric_limits<double>::infinity();
    for (int q = 0; q < np; ++q)
      for (auto n : {m.sp_a[i * np + q], m.sp_b[i * np + q]})
        k = std::min(k, eta * omega2_max * m.mass[n] / (2.0 * count[n]));
    if (!std::isfinite(k)) continue;
    // The springs mode's constants give E/h A_c (k_n A_c / alpha) and the ratio G/E.
    const double kn_old = m.sp_kn.v[i], ks_old = m.sp_ks.v[i];
    const double alpha = m.iface_materials[m.iface_material[i]].stiffness_factor;
    if (kn_old > 0) ratio.push_back(k / (kn_old / alpha));
    m.sp_kn.v[i] = k;
    m.sp_ks.v[i] = kn_old > 0 ? k * (ks_old / kn_old) : k;
  }
  OpenedStiffness out;
  if (!ratio.empty()) {
    std::sort(ratio.begin(), ratio.end());
    out.ratio_min = ratio.front();
    out.ratio_median = ratio[ratio.size() / 2];
  }
  return out;
}

}  // namespace cdem
