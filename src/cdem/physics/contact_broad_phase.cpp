// General contact's broad phase (physics/contact.hpp): the bodies, the candidate faces and
// nodes, the (node, block) pairs found through a hashed cell grid, the previous pairs' state
// carried over, and the lists derived from the pairs. Split from contact.cpp, which keeps the
// set-up and the per-step narrow phase.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {
namespace {

// The nodes of block face slot f (4 b + k), outward order; returns their count (2 or 3).
inline int face_nodes(const Model& m, std::int32_t f, std::int32_t* q) {
  const std::int32_t b = f / 4, k = f % 4;
  const LocalFaces lf = local_faces(m.block_type[b]);
  const std::int32_t n0 = m.block_first_node[b];
  for (int i = 0; i < lf.nodes_per_face; ++i) q[i] = n0 + lf.f[k][i];
  return lf.nodes_per_face;
}

std::int32_t find_root(std::vector<std::int32_t>& p, std::int32_t x) {
  while (p[x] != x) x = p[x] = p[p[x]];
  return x;
}
// Are nodes n and q (split from one vertex) bonded: tied in one cluster, or joined by a spring
// point that is not released (that point is their contact)?
bool bonded(const Model& m, std::int32_t n, std::int32_t q) {
  const std::int32_t b = m.node_block(static_cast<std::size_t>(n));
  const int np = m.springs_per_iface;
  for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
    const std::int32_t code = m.block_iface_list[e];
    const bool a_side = code > 0;
    const std::size_t s0 = static_cast<std::size_t>(block_iface_index(code)) * np;
    for (int i = 0; i < np; ++i) {
      const std::size_t s = s0 + i;
      const std::int32_t mine = a_side ? m.sp_a[s] : m.sp_b[s];
      const std::int32_t other = a_side ? m.sp_b[s] : m.sp_a[s];
      if (mine == n && other == q) return m.sp_state[s] != kReleased || (m.tied && m.sp_tied[s]);
    }
  }
  return false;
}

inline std::uint64_t cell_hash(std::int64_t i, std::int64_t j, std::int64_t k) {
  return static_cast<std::uint64_t>(i) * 73856093ULL ^ static_cast<std::uint64_t>(j) * 19349663ULL ^
         static_cast<std::uint64_t>(k) * 83492791ULL;
}

}  // namespace

void rebuild_contact_pairs(Model& m, ContactSet& cs, double dt) {
  const std::size_t nb = m.n_blocks(), ni = m.n_ifaces();
  const int np = m.springs_per_iface;
  ++cs.rebuilds;
  // The previous pairs: their state is carried over to the new list at the end, in place.
  cs.pair_node.swap(cs.pair_node_prev);
  cs.pair_block.swap(cs.pair_block_prev);
  const std::vector<std::int32_t>& old_node = cs.pair_node_prev;
  const std::vector<std::int32_t>& old_face = cs.pair_block_prev;
  if (cs.node_drift.size() != m.n_nodes()) reset_contact_sleep(m, cs);  // (the first build)
  // 0. The half skins: each block's own (no skin asked), raised for a fast block to what it
  // covers in kSkinSteps steps at its present speed (at most kSkinCap x skin). A pair is listed
  // when the node lies within sigma_n + sigma_b of the block's box and the list is rebuilt once a
  // node has moved more than its sigma, whatever the sigmas: a larger one for a block that flies
  // only lists its pairs farther out, and its nodes trigger the next build later.
  if (cs.cfg.skin <= 0 && cs.half_skin0.size() == nb && dt > 0) {
    const double per_speed = kSkinSteps * dt, cap = kSkinCap * cs.skin;
#pragma omp parallel for schedule(static)
    for (std::int64_t b = 0; b < static_cast<std::int64_t>(nb); ++b) {
      double v2 = 0;
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) v2 = std::max(v2, dot(m.v[n], m.v[n]));
      cs.half_skin[b] = std::max(cs.half_skin0[b], std::min(std::sqrt(v2) * per_speed, cap));
    }
  }
  // 1. Bodies: blocks connected through points that are not released.
  cs.body.resize(nb);
  std::iota(cs.body.begin(), cs.body.end(), 0);
  std::vector<std::uint8_t> iface_released(ni, 0), iface_cracked(ni, 0);
  for (std::size_t i = 0; i < ni; ++i) {
    bool joined = false, released = false, cracked = false;
    for (int q = 0; q < np; ++q) {
      const auto st = m.sp_state[i * np + q];
      joined = joined || st != kReleased;
      released = released || st == kReleased;
      cracked = cracked || st != kIntact;
    }
    iface_released[i] = released;
    iface_cracked[i] = cracked;
    if (joined) {
      const auto ra = find_root(cs.body, m.iface_block_a[i]), rb = find_root(cs.body, m.iface_block_b[i]);
      if (ra != rb) cs.body[std::max(ra, rb)] = std::min(ra, rb);
    }
  }
  for (std::size_t b = 0; b < nb; ++b) cs.body[b] = find_root(cs.body, static_cast<std::int32_t>(b));
  // 2. Candidate faces: boundary faces and faces of interfaces with a released point.
  cs.cand_faces.clear();
  cs.on_released.assign(m.n_nodes(), 0);
  cs.face_cand.assign(cs.face_iface.size(), 0);
  std::int32_t q[3];
  for (std::size_t f = 0; f < cs.face_iface.size(); ++f) {
    const std::int32_t b = static_cast<std::int32_t>(f / 4), k = static_cast<std::int32_t>(f % 4);
    if (k >= local_faces(m.block_type[b]).count) continue;
    if (!m.no_contact.empty() && m.no_contact[b]) continue;  // (a collapsed explosive block)
    const std::int32_t i = cs.face_iface[f];
    if (i >= 0 && !(cs.cfg.cracked_faces ? iface_cracked[i] : iface_released[i])) continue;
    cs.cand_faces.push_back(static_cast<std::int32_t>(f));
    cs.face_cand[f] = 1;
    if (i >= 0 && iface_released[i]) {
      const int c = face_nodes(m, static_cast<std::int32_t>(f), q);
      for (int j = 0; j < c; ++j) cs.on_released[q[j]] = 1;
    }
  }
  // 3. Candidate nodes: the nodes of the candidate faces.
  cs.cand_nodes.clear();
  for (auto f : cs.cand_faces) {
    const int c = face_nodes(m, f, q);
    for (int j = 0; j < c; ++j) cs.cand_nodes.push_back(q[j]);
  }
  std::sort(cs.cand_nodes.begin(), cs.cand_nodes.end());
  cs.cand_nodes.erase(std::unique(cs.cand_nodes.begin(), cs.cand_nodes.end()), cs.cand_nodes.end());
  cs.x_build.resize(cs.cand_nodes.size());
  for (std::size_t j = 0; j < cs.cand_nodes.size(); ++j) cs.x_build[j] = m.x[cs.cand_nodes[j]];
  // 4. Grid: the box of each block with a candidate face, grown by its half skin sigma_b,
  // registered in every cell it overlaps; each node looks up the cells its own box (grown by its
  // sigma_n) overlaps, and a pair is kept when the node lies in the block's box grown by
  // sigma_b + sigma_n. A node outside it cannot reach the block before the next build (it moves
  // less than sigma_n, the block's nodes less than sigma_b). Cell size: the median box grown by
  // 2 sigma_b on each side (with one skin everywhere, the box grown by the skin), so a box
  // covers 2^dim cells or a few more; at twice that, a node's cell held 8 times as many boxes to
  // test, most of the rebuild's time in the late SPEC 5.3 cylinder. (Boxes of the candidate
  // faces grown by the skin and half the block's size, as before, held 3-5 times as many nodes
  // per block in a graded mesh: small blocks near a large one.)
  std::vector<std::int32_t> cand_block;     // ascending
  std::vector<std::uint8_t> cand_released;  // the block has a candidate face that is released
  for (const auto f : cs.cand_faces) {
    const std::int32_t bf = f / 4;
    if (cand_block.empty() || cand_block.back() != bf) cand_block.push_back(bf), cand_released.push_back(0);
    if (cs.face_iface[f] >= 0 && iface_released[cs.face_iface[f]]) cand_released.back() = 1;
  }
  const std::size_t nf = cand_block.size();
  // the trigger's other nodes: those of the candidate blocks off every candidate face
  // (the blocks ascend and own contiguous node ranges, so their nodes ascend: one walk through
  // the sorted candidate nodes instead of a search for each)
  cs.watch_nodes.clear();
  std::size_t cn = 0;
  for (const auto bf : cand_block)
    for (auto qn = m.block_first_node[bf]; qn < m.block_first_node[bf + 1]; ++qn) {
      while (cn < cs.cand_nodes.size() && cs.cand_nodes[cn] < qn) ++cn;
      if (cn == cs.cand_nodes.size() || cs.cand_nodes[cn] != qn) cs.watch_nodes.push_back(qn);
    }
  cs.watch_x.resize(cs.watch_nodes.size());
  for (std::size_t j = 0; j < cs.watch_nodes.size(); ++j) cs.watch_x[j] = m.x[cs.watch_nodes[j]];
  std::vector<Vec3> lo(nf), hi(nf);  // the block's box (not grown)
  std::vector<double> ext(nf);
  double reach = 0;                  // the largest |coordinate| of the boxes
  for (std::size_t j = 0; j < nf; ++j) {
    const std::int32_t bf = cand_block[j];
    m.block_box(static_cast<std::size_t>(bf), lo[j], hi[j]);
    const Vec3 a = lo[j], b = hi[j];
    for (int d = 0; d < cs.dim; ++d) reach = std::max({reach, std::abs(a[d]), std::abs(b[d])});
    double e = 0;
    for (int d = 0; d < cs.dim; ++d) e = std::max(e, b[d] - a[d]);
    ext[j] = e + 4.0 * cs.half_skin[bf];
  }
  cs.pair_node.clear();
  cs.pair_block.clear();
  if (nf > 0 && !cs.cand_nodes.empty()) {
    std::vector<double> sorted_ext = ext;
    std::nth_element(sorted_ext.begin(), sorted_ext.begin() + nf / 2, sorted_ext.end());
    const double cell = std::max(sorted_ext[nf / 2], 1e-12);
    // (the registered boxes are padded by a hair of a cell and a few rounding units of the
    // largest coordinate, so that rounding in the two grown boxes cannot hide a cell the exact
    // test below would accept, even far from the origin)
    const double pad = 1e-9 * cell + 8 * std::numeric_limits<double>::epsilon() * reach;
    std::size_t tsize = 1;
    while (tsize < 2 * nf) tsize <<= 1;
    const std::uint64_t mask = tsize - 1;
    auto idx = [&](double v) { return static_cast<std::int64_t>(std::floor(v / cell)); };
    auto for_cells = [&](const Vec3& a, const Vec3& b, auto&& fn) {
      const std::int64_t i0 = idx(a.x), i1 = idx(b.x), j0 = idx(a.y), j1 = idx(b.y);
      const std::int64_t k0 = cs.dim == 3 ? idx(a.z) : 0, k1 = cs.dim == 3 ? idx(b.z) : 0;
      for (auto i = i0; i <= i1; ++i)
        for (auto j = j0; j <= j1; ++j)
          for (auto k = k0; k <= k1; ++k) fn(cell_hash(i, j, k) & mask);
    };
    auto block_cells = [&](std::size_t j, auto&& fn) {
      const double g = cs.half_skin[cand_block[j]] + pad;
      for_cells(lo[j] - Vec3{g, g, g}, hi[j] + Vec3{g, g, g}, fn);
    };
    // (what the node search below reads of each candidate block, in one cache line per block:
    // the box, the half skin, the block, its released flag; the same values as in the arrays
    // above, so the same tests, bit for bit. Read from four arrays, one of them through the
    // block's index, the test of a box cost several cache misses: most of the rebuild's time)
    struct alignas(64) CandBox {
      Vec3 lo, hi;
      double half_skin;
      std::int32_t block;
      std::uint8_t released;
    };
    std::vector<CandBox> box(nf);
    for (std::size_t j = 0; j < nf; ++j)
      box[j] = {lo[j], hi[j], cs.half_skin[cand_block[j]], cand_block[j], cand_released[j]};
    cs.bucket_offset.assign(tsize + 1, 0);
    for (std::size_t j = 0; j < nf; ++j) block_cells(j, [&](std::uint64_t h) { ++cs.bucket_offset[h + 1]; });
    for (std::size_t h = 0; h < tsize; ++h) cs.bucket_offset[h + 1] += cs.bucket_offset[h];
    const std::int32_t nentry = cs.bucket_offset[tsize];
    cs.bucket_entry.resize(nentry);
    cs.bucket_key.resize(nentry);
    cs.bucket_run_end.resize(nentry);
    {
      // (the boxes in the order of their keys, so that in each bucket the entries of one key
      // form one run, which the node search below passes over in one step)
      std::vector<std::uint64_t> order(nf);
      for (std::size_t j = 0; j < nf; ++j)
        order[j] = (std::uint64_t{2 * static_cast<std::uint32_t>(cs.body[cand_block[j]]) + cand_released[j]} << 32) | j;
      std::sort(order.begin(), order.end());
      std::vector<std::int32_t> fill(cs.bucket_offset.begin(), cs.bucket_offset.end() - 1);
      for (const std::uint64_t o : order) {
        const auto j = static_cast<std::size_t>(o & 0xffffffffu);
        block_cells(j, [&](std::uint64_t h) {
          cs.bucket_key[fill[h]] = static_cast<std::uint32_t>(o >> 32);
          cs.bucket_entry[fill[h]++] = static_cast<std::int32_t>(j);
        });
      }
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t h = 0; h < static_cast<std::int64_t>(tsize); ++h)
      for (auto e = cs.bucket_offset[h + 1] - 1; e >= cs.bucket_offset[h]; --e)
        cs.bucket_run_end[e] = e + 1 < cs.bucket_offset[h + 1] && cs.bucket_key[e + 1] == cs.bucket_key[e] ? cs.bucket_run_end[e + 1] : e + 1;
    // 5. Pairs, node by node (ascending), blocks ascending: each thread takes a contiguous
    // range of the candidate nodes and lists its pairs; the lists are joined in thread order, so
    // the pairs are the same, in the same order, for any thread count.
    const auto ncn = static_cast<std::int64_t>(cs.cand_nodes.size());
    const int nt = omp_get_max_threads();
    std::vector<std::vector<std::int32_t>> t_node(nt), t_block(nt);
#pragma omp parallel num_threads(nt)
    {
      const auto t = static_cast<std::int64_t>(omp_get_thread_num());
      const auto ntt = static_cast<std::int64_t>(omp_get_num_threads());
      std::vector<std::int32_t> near_blocks;
      std::vector<std::int32_t>& out_node = t_node[static_cast<std::size_t>(t)];
      std::vector<std::int32_t>& out_block = t_block[static_cast<std::size_t>(t)];
      std::int32_t bn = 0;  // the node's block, found by walking up (the nodes ascend)
      for (std::int64_t jn = ncn * t / ntt; jn < ncn * (t + 1) / ntt; ++jn) {
        const std::int32_t n = cs.cand_nodes[static_cast<std::size_t>(jn)];
        const Vec3 x = m.x[n];
        if (jn == ncn * t / ntt) bn = m.node_block(static_cast<std::size_t>(n));
        while (m.block_first_node[bn + 1] <= n) ++bn;
        const double sn = cs.half_skin[bn];
        // (a block of the node's own body without a released candidate face pairs with it only
        // if the node is on a released face: the test below, by the entries' key alone, their run
        // in the bucket at once. In a cracked model most boxes around a node are of its own
        // body, and reading each box was most of the rebuild's time with candidates = "cracked")
        const std::uint32_t own = cs.on_released[n] ? std::numeric_limits<std::uint32_t>::max()
                                                    : 2 * static_cast<std::uint32_t>(cs.body[bn]);
        near_blocks.clear();
        for_cells(x - Vec3{sn, sn, sn}, x + Vec3{sn, sn, sn}, [&](std::uint64_t h) {
          for (auto e = cs.bucket_offset[h]; e < cs.bucket_offset[h + 1]; ++e) {
            if (cs.bucket_key[e] == own) {
              e = cs.bucket_run_end[e] - 1;
              continue;
            }
            const CandBox& cb = box[static_cast<std::size_t>(cs.bucket_entry[e])];
            const std::int32_t bf = cb.block;
            const double g = cb.half_skin + sn;
            bool inside = true;
            for (int d = 0; d < cs.dim; ++d) inside = inside && x[d] >= cb.lo[d] - g && x[d] <= cb.hi[d] + g;
            if (!inside) continue;
            if (bf == bn) continue;
            const bool released = cs.on_released[n] || cb.released;
            if (cs.body[bf] == cs.body[bn] && !released) continue;
            near_blocks.push_back(bf);
          }
        });
        std::sort(near_blocks.begin(), near_blocks.end());
        near_blocks.erase(std::unique(near_blocks.begin(), near_blocks.end()), near_blocks.end());
        for (auto bf : near_blocks) {
          bool skip = false;
          for (auto qn = m.block_first_node[bf]; qn < m.block_first_node[bf + 1] && !skip; ++qn)
            skip = m.node_vertex[qn] == m.node_vertex[n] && bonded(m, n, qn);
          if (skip) continue;
          out_node.push_back(n);
          out_block.push_back(bf);
        }
      }
    }
    std::size_t total = 0;  // (the same for any thread count, and so the buffers' size)
    for (int t = 0; t < nt; ++t) total += t_node[t].size();
    cs.pairs_high = std::max(cs.pairs_high, total);
    if (cs.pair_node.capacity() < total) {
      std::vector<std::int32_t>().swap(cs.pair_node);
      std::vector<std::int32_t>().swap(cs.pair_block);
      cs.pair_node.reserve(cs.pairs_high);
      cs.pair_block.reserve(cs.pairs_high);
    }
    for (int t = 0; t < nt; ++t) {
      cs.pair_node.insert(cs.pair_node.end(), t_node[t].begin(), t_node[t].end());
      cs.pair_block.insert(cs.pair_block.end(), t_block[t].begin(), t_block[t].end());
    }
  }
  // 6. Carry the state of the pairs that stay (both lists sorted by (node, block)): the merge
  // gives each new pair its old index, by which every per-pair array is permuted in place (no
  // second copy of the pairs' state). A pair that is dropped while holding elastic energy books it
  // as dissipated (the balance stays closed). The pairs that stay keep their wakes: the sleep's
  // bounds rest on the nodes' path lengths, which a rebuild does not reset, so a pair found far
  // apart before the rebuild is not tested again at it (before 4 Dec 2026 every pair was, at the
  // step after each rebuild: the same results, bit for bit, at the cost of a step that tested all).
  const std::size_t npair = cs.pair_node.size();
  {
    cs.pair_from.resize(npair);
    std::size_t o = 0;
    const std::size_t nold = old_node.size();
    auto older = [&](std::size_t a, std::size_t p) {
      return old_node[a] != cs.pair_node[p] ? old_node[a] < cs.pair_node[p] : old_face[a] < cs.pair_block[p];
    };
    auto drop = [&](std::size_t a) {
      cs.diss_closed += cs.pair_diss[a];
      if (cs.pair_k[a] > 0)
        cs.diss_closed += 0.5 * cs.pair_k[a] * cs.pair_gap[a] * cs.pair_gap[a] +
                          0.5 * dot(cs.pair_ft[a], cs.pair_ft[a]) / (cs.shear_ratio * cs.pair_k[a]);
    };
    for (std::size_t p = 0; p < npair; ++p) {
      while (o < nold && older(o, p)) drop(o++);
      const bool same = o < nold && old_node[o] == cs.pair_node[p] && old_face[o] == cs.pair_block[p];
      cs.pair_from[p] = same ? static_cast<std::int32_t>(o++) : -1;
    }
    while (o < nold) drop(o++);
  }
  // (each array on its own: one task each, in parallel; then the pairs' stiffness, the smallest
  // of the node's and the block nodes' budgets)
#pragma omp parallel for schedule(dynamic, 1)
  for (int task = 0; task < 10; ++task) {
    switch (task) {
      case 0: carry_monotone(cs.pair_fn, cs.pair_from, 0.0); break;
      case 1: carry_monotone(cs.pair_diss, cs.pair_from, 0.0); break;
      case 2: carry_monotone(cs.pair_gap, cs.pair_from, 0.0); break;
      case 3: carry_monotone(cs.pair_g0, cs.pair_from, 0.0); break;
      case 4: carry_monotone(cs.pair_ft, cs.pair_from, Vec3{}); break;
      case 5: carry_monotone(cs.pair_force, cs.pair_from, Vec3{}); break;
      case 6: carry_monotone(cs.pair_kf, cs.pair_from, std::int8_t{-1}); break;
      case 7: carry_monotone(cs.pair_wake, cs.pair_from, 0.0); break;  // (a new pair: tested next step)
      case 8: carry_monotone(cs.pair_gwake, cs.pair_from, 0.0f); break;
      default:
        cs.pair_k.resize(npair);
        for (std::size_t p = 0; p < npair; ++p) {
          const std::int32_t b = cs.pair_block[p];
          double k = cs.kc[cs.pair_node[p]];
          for (auto qn = m.block_first_node[b]; qn < m.block_first_node[b + 1]; ++qn) k = std::min(k, cs.kc[qn]);
          cs.pair_k[p] = k;
        }
    }
  }
  // 7. The lists derived from the pairs.
  index_pairs(m, cs);
  cs.released_seen = m.released_points;
  cs.release_drift = 0;
  reset_release_trigger(m, cs);
  cs.rebuild_due = false;
}

void reset_contact_sleep(const Model& m, ContactSet& cs) {
  cs.node_drift.assign(m.n_nodes(), 0.0);
  cs.blk_drift.assign(m.n_blocks(), 0.0);
  cs.grp_clock.assign((m.n_blocks() + kSleepGroup - 1) / kSleepGroup, 0.0);
  cs.grp_speed.assign(cs.grp_clock.size(), 0.0);
  std::fill(cs.pair_wake.begin(), cs.pair_wake.end(), 0.0);
  std::fill(cs.pair_gwake.begin(), cs.pair_gwake.end(), 0.0f);
  std::fill(cs.bp_wake.begin(), cs.bp_wake.end(), 0.0);
}

void index_pairs(const Model& m, ContactSet& cs) {
  // The distinct blocks of the pairs (their bounding spheres are computed once per step for the
  // quick reject) and the step's work lists, sized here so that a step allocates nothing.
  const std::size_t npair = cs.pair_node.size();
  // the rebuild trigger's limit per watched node (ascending): its block's sigma, squared
  auto limits = [&](const std::vector<std::int32_t>& nodes, std::vector<double>& lim2) {
    lim2.resize(nodes.size());
    for (std::size_t j = 0, b = 0; j < nodes.size(); ++j) {
      while (m.block_first_node[b + 1] <= nodes[j]) ++b;
      lim2[j] = cs.half_skin[b] * cs.half_skin[b];
    }
  };
  limits(cs.cand_nodes, cs.cand_lim2);
  limits(cs.watch_nodes, cs.watch_lim2);
  cs.block_slot.assign(m.n_blocks(), -1);
  cs.cblock.clear();
  cs.pair_cb.resize(npair);
  for (std::size_t p = 0; p < npair; ++p) {
    std::int32_t& slot = cs.block_slot[cs.pair_block[p]];
    if (slot < 0) {
      slot = static_cast<std::int32_t>(cs.cblock.size());
      cs.cblock.push_back(cs.pair_block[p]);
    }
    cs.pair_cb[p] = slot;
  }
  cs.cb_geom.resize(cs.cblock.size());
  cs.pair_g.resize(npair);
  cs.pair_score.resize(npair);
  cs.pair_kf_now.resize(npair);
  cs.pair_margin.resize(npair);
  cs.pair_n.resize(npair);
  cs.pair_w.resize(npair);  // (written for the near pairs before they are read, each step)
  cs.near_scratch.resize(npair);
  cs.pair_off.assign(npair, 0);
  cs.pair_wake.resize(npair, 0.0);  // (a rebuild carried them over; after loading: reset_contact_sleep)
  cs.pair_gwake.resize(npair, 0.0f);
  cs.cb_pair_start.assign(cs.cblock.size() + 1, 0);
  for (std::size_t p = 0; p < npair; ++p) ++cs.cb_pair_start[cs.pair_cb[p] + 1];
  for (std::size_t j = 0; j < cs.cblock.size(); ++j) cs.cb_pair_start[j + 1] += cs.cb_pair_start[j];
  cs.cb_pair.resize(npair);
  {
    std::vector<std::int32_t> fill(cs.cb_pair_start.begin(), cs.cb_pair_start.end() - 1);
    for (std::size_t p = 0; p < npair; ++p) cs.cb_pair[fill[cs.pair_cb[p]]++] = static_cast<std::int32_t>(p);
  }
  cs.cb_drift.assign(2 * cs.cblock.size(), 0.0);
  // The sleep's groups (contact.cpp): the pairs of each group's nodes (a range: the pairs are
  // sorted by node, and the nodes of a block are consecutive), and the groups whose speeds bound
  // the motion of those nodes and of their pairs' blocks (the group itself first, then the
  // blocks' groups, distinct, in the order of the pairs).
  {
    const std::size_t ng = (m.n_blocks() + kSleepGroup - 1) / kSleepGroup;
    if (cs.grp_clock.size() != ng) {  // (the first index: no pair has a wake on a clock yet)
      cs.grp_clock.assign(ng, 0.0);
      cs.grp_speed.assign(ng, 0.0);
    }
    cs.grp_pair_start.assign(ng + 1, 0);
    cs.grp_nbr_start.assign(ng + 1, 0);
    cs.grp_nbr.clear();
    std::vector<std::int32_t> stamp(ng, -1);  // (per group the last group that listed it)
    std::int32_t b = 0;  // the block of the pair's node, found by walking up (the nodes ascend)
    std::size_t p = 0;
    for (std::size_t g = 0; g < ng; ++g) {
      const auto gi = static_cast<std::int32_t>(g);
      cs.grp_pair_start[g] = static_cast<std::int32_t>(p);
      const std::size_t first = cs.grp_nbr.size();
      for (; p < npair; ++p) {
        const std::int32_t n = cs.pair_node[p];
        while (m.block_first_node[b + 1] <= n) ++b;
        if (static_cast<std::size_t>(b) / kSleepGroup != g) break;
        if (cs.grp_nbr.size() == first) stamp[g] = gi, cs.grp_nbr.push_back(gi);  // (itself first)
        const auto h = static_cast<std::int32_t>(cs.pair_block[p] / kSleepGroup);
        if (stamp[h] != gi) stamp[h] = gi, cs.grp_nbr.push_back(h);
      }
      cs.grp_nbr_start[g + 1] = static_cast<std::int32_t>(cs.grp_nbr.size());
    }
    cs.grp_pair_start[ng] = static_cast<std::int32_t>(npair);
  }
  cs.face_touched.reserve(4 * cs.cblock.size());
  cs.face_sum.reserve(4 * cs.cblock.size());
  cs.near.reserve(npair);
  cs.near_node.reserve(npair);
  cs.near_forced.reserve(npair);
  cs.near_dd.reserve(npair);
  cs.near_group.reserve(npair + 1);
  cs.near_count.assign(static_cast<std::size_t>(omp_get_max_threads()) + 1, 0);
  index_edge_pairs(m, cs);
}

}  // namespace cdem
