// Edge-to-edge contact in 3D (physics/contact.hpp, docs/theory.md "General contact").
//
// Node-to-face contact alone cannot hold two blocks whose faces overlap offset: a cube resting on
// another shifted sideways touches it at two vertices only (one of each cube), on a diagonal, and
// rocks about it, while its crossing edges pass into each other (tests/verification/
// test_contact.cpp, the shifted stack). Here a candidate edge of block A (an edge of a candidate
// face) that crosses a candidate edge of block B of another body is pushed out along their common
// normal:
//   closest points pa = p0 + s (p1 - p0), pb = q0 + t (q1 - q0) of the two lines, both inside
//   their segments (0.01 < s, t < 0.99: at an end the vertex is a node-to-face contact);
//   n = (p1 - p0) x (q1 - q0) / |...|, turned to point out of B (n . (m1 + m2) > 0, m the outward
//   normals of B's two faces at its edge) and into A's side (n . A's pair < 0);
//   penetrating when pa is inside B and pb inside A (all face planes within tol) and
//   d = (pb - pa) . n > 0;
//   F = max(0, k (d - d0) - c v_n) n on A's edge, split (1 - s, s) over its nodes, and -F on B's,
//   (1 - t, t): equal and opposite, so momentum is kept to round-off. k: a quarter of the
//   smallest contact stiffness of the four nodes (kEdgeShare), c = 2 zeta sqrt(k m) with m
//   the smallest of their masses; d0 as for nodes: the depth beyond two steps' approach at
//   first touch (beyond one step's approach, approach = max(0, -v_n)) is ignored, then only
//   shrinks while the crossing presses; inside an overlap the node contacts ignore (a node of
//   one block holding a contact in the other's body with an ignored depth) a crossing not
//   pressing ignores all its depth, each step, so it takes no force while that lasts. Coulomb
//   friction as
//   for the node pairs (a tangential spring k_t = k G/E capped at mu F_n).
// Energy: stored k (d - d0)^2 / 2 + |F_t|^2 / 2 k_t; the dissipation per contact is the work done on it (the
// trapezoidal F . du with du = dt (v_a - v_b) at the closest points) minus the change of that
// energy, as for the node pairs. A contact that ends books its last step the same way; one that
// is dropped (its blocks no longer paired) books its stored energy as dissipated.
//
// Which block pairs: those with a node-to-block candidate pair either way, of different bodies,
// both tetrahedra (index_edge_pairs, at each rebuild). Each step, per block pair in parallel
// (those found apart sleep while they cannot have come together: (1) below): a
// bounding-sphere test of the two blocks, a separating face plane (all four nodes of one in
// front of a face of the other: they cannot overlap), then per edge pair a sphere test of the
// two edges, then the closest points. Two passes (count, then fill at fixed offsets) keep the contact list
// sorted by (block pair, edge, edge) for any thread count; the forces are gathered serially in
// that order: bitwise the same for any thread count.
#include <omp.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "cdem/core/loop_split.hpp"
#include "cdem/core/prefetch.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/contact.hpp"
#include "cdem/physics/contact_edge_geometry.hpp"

namespace cdem {
namespace {

// f(last step's array, this step's array) for every per-contact array of the edge contacts: the
// list is resized, compacted and swapped through this one list of its fields.
template <class F>
void for_each_edge_array(ContactSet& cs, F&& f) {
  f(cs.ec_a, cs.ecn_a);
  f(cs.ec_b, cs.ecn_b);
  f(cs.ec_key, cs.ecn_key);
  f(cs.ec_d0, cs.ecn_d0);
  f(cs.ec_gap, cs.ecn_gap);
  f(cs.ec_k, cs.ecn_k);
  f(cs.ec_diss, cs.ecn_diss);
  f(cs.ec_s, cs.ecn_s);
  f(cs.ec_t, cs.ecn_t);
  f(cs.ec_force, cs.ecn_force);
  f(cs.ec_ft, cs.ecn_ft);
}

// An edge contact's stiffness, as a share of its nodes' smallest contact stiffness: a node is an
// end of three edges of its tet, each of which may cross several edges at once where faces lie
// on faces (a cube on a finer base: 12 crossings under 4 nodes), beside its own node-to-face
// contact. At the full budget the offset impact of test_contact.cpp gained 0.43 % of its energy
// and an aligned stack was jolted off its vertex contacts; at 1/2 and 1/4 both behave (impact:
// +0.19 %, +0.33 % booked as losses). 1/4 keeps the sum a node can feel within its budget of
// three contacts with one node contact and four edge contacts.
constexpr double kEdgeShare = 0.25;

// The previous step's contact of block pair (a, b) and edge pair `key` within [lo, hi), the
// previous contacts of that block pair (prev_begin), or -1.
std::int64_t find_prev(const ContactSet& cs, std::int64_t lo, std::int64_t hi, std::int32_t key) {
  for (std::int64_t q = lo; q < hi; ++q)
    if (cs.ec_key[q] == key) return q;
  return -1;
}

// Does a node of block a hold a node-to-face contact in b's body whose depth is ignored (d0
// beyond the holding block's tolerance: an overlap inherited, not approached)? Not counted: a
// node off its contact face (its whole depth ignored for that reason: a vertex sliding past
// the face's edge, where the edge contacts are what should hold). The node pairs of this step
// (contact.cpp runs before the edges), sorted by node.
// The keys of the previous step's contacts of a block pair, [lo, hi), as bits.
std::uint64_t prev_keys(const ContactSet& cs, std::int64_t lo, std::int64_t hi) {
  std::uint64_t keys = 0;
  for (std::int64_t q = lo; q < hi; ++q) keys |= std::uint64_t{1} << cs.ec_key[q];
  return keys;
}

bool holds_ignored_overlap(const Model& m, const ContactSet& cs, std::int32_t a, std::int32_t b) {
  const std::int32_t body_b = cs.body[b];
  for (auto n = m.block_first_node[a]; n < m.block_first_node[a + 1]; ++n)
    for (auto it = std::lower_bound(cs.pair_node.begin(), cs.pair_node.end(), n); it != cs.pair_node.end() && *it == n;
         ++it) {
      const auto p = static_cast<std::size_t>(it - cs.pair_node.begin());
      const std::int32_t pb = cs.pair_block[p];
      if (cs.pair_kf[p] >= 0 && !cs.pair_off[p] && cs.body[pb] == body_b && cs.pair_g0[p] > 1e-3 * m.block_size[pb])
        return true;
    }
  return false;
}

}  // namespace

void index_edge_pairs(const Model& m, ContactSet& cs) {
  // the previous block pairs and their wakes (the block pairs that stay keep them: their bounds
  // rest on the nodes' path lengths, which a rebuild does not reset; contact_broad_phase.cpp)
  std::vector<std::int32_t> old_a, old_b;
  std::vector<double> old_wake;
  old_a.swap(cs.bp_a);
  old_b.swap(cs.bp_b);
  old_wake.swap(cs.bp_wake);
  if (!cs.edges || m.dim != 3) return;
  // The block pairs (lo, hi) of the node pairs, ascending and distinct: a counting sort on lo
  // (linear; the node pairs are sorted by node, so each node's block follows from the last one
  // without a search), then each lo's few his sorted and made unique.
  const std::size_t nb = m.n_blocks(), npair = cs.pair_node.size();
  std::vector<std::int32_t> off(nb + 1, 0), his;
  auto for_each_pair = [&](auto&& fn) {
    std::int32_t a = 0;
    for (std::size_t p = 0; p < npair; ++p) {
      const std::int32_t n = cs.pair_node[p], b = cs.pair_block[p];
      while (m.block_first_node[a + 1] <= n) ++a;
      if (a == b || cs.body[a] == cs.body[b]) continue;
      if (m.block_type[a] != ElemType::Tet4 || m.block_type[b] != ElemType::Tet4) continue;
      fn(std::min(a, b), std::max(a, b));
    }
  };
  for_each_pair([&](std::int32_t lo, std::int32_t) { ++off[lo + 1]; });
  for (std::size_t b = 0; b < nb; ++b) off[b + 1] += off[b];
  his.resize(static_cast<std::size_t>(off[nb]));
  {
    std::vector<std::int32_t> fill(off.begin(), off.end() - 1);
    for_each_pair([&](std::int32_t lo, std::int32_t hi) { his[fill[lo]++] = hi; });
  }
  for (std::size_t lo = 0; lo < nb; ++lo) {
    const auto first = his.begin() + off[lo], last = his.begin() + off[lo + 1];
    std::sort(first, last);
    for (auto it = first; it != last; ++it)
      if (it == first || *it != *(it - 1)) {
        cs.bp_a.push_back(static_cast<std::int32_t>(lo));
        cs.bp_b.push_back(*it);
      }
  }
  // the distinct blocks, ascending, and each pair's two slots among them (off reused: the slot)
  std::fill(off.begin(), off.end(), -1);
  for (std::size_t j = 0; j < cs.bp_a.size(); ++j) off[cs.bp_a[j]] = off[cs.bp_b[j]] = 0;
  cs.eb_block.clear();
  for (std::size_t b = 0; b < nb; ++b)
    if (off[b] == 0) {
      off[b] = static_cast<std::int32_t>(cs.eb_block.size());
      cs.eb_block.push_back(static_cast<std::int32_t>(b));
    }
  cs.bp_ia.resize(cs.bp_a.size());
  cs.bp_ib.resize(cs.bp_a.size());
  for (std::size_t j = 0; j < cs.bp_a.size(); ++j) {
    cs.bp_ia[j] = off[cs.bp_a[j]];
    cs.bp_ib[j] = off[cs.bp_b[j]];
  }
  const std::size_t neb = cs.eb_block.size();
  cs.eb_need.assign(neb, 0);
  cs.eb_geom.resize(neb);
  cs.eb_drift.assign(2 * neb, 0.0);
  cs.bp_wake.assign(cs.bp_a.size(), 0.0);  // a new block pair is tested at the next step
  if (old_wake.size() == old_a.size())
    for (std::size_t j = 0, o = 0; j < cs.bp_a.size(); ++j) {  // (both lists sorted by (a, b))
      while (o < old_a.size() && (old_a[o] < cs.bp_a[j] || (old_a[o] == cs.bp_a[j] && old_b[o] < cs.bp_b[j]))) ++o;
      if (o < old_a.size() && old_a[o] == cs.bp_a[j] && old_b[o] == cs.bp_b[j]) cs.bp_wake[j] = old_wake[o];
    }
  cs.bp_count.assign(cs.bp_a.size() + 1, 0);
  cs.bp_prev.assign(cs.bp_a.size() + 1, 0);
  cs.bp_prev_n.assign(cs.bp_a.size(), 0);
  cs.bp_hits.assign(cs.bp_a.size(), 0);
  cs.bp_scratch.resize(cs.bp_a.size());
  cs.bp_awake_count.assign(static_cast<std::size_t>(omp_get_max_threads()) + 1, 0);  // (a step allocates nothing)
  cs.bp_prev_set.clear();  // (bp_prev_n is 0 everywhere)
  cs.bp_awake.reserve(cs.bp_a.size());
  // room for the contacts without allocating in a step (grown only if a step needs more)
  const std::size_t room = std::max<std::size_t>(64, 2 * static_cast<std::size_t>(cs.ec_active_max));
  for_each_edge_array(cs, [&](auto&, auto& now) { now.reserve(room); });
  cs.bp_prev_set.reserve(room);
}

void locate_edge_penetration(const Model& m, ContactSet& cs, double ratio) {
  for (std::size_t i = 0; i < cs.ec_gap.size(); ++i) {
    const std::int32_t a = cs.ec_a[i], b = cs.ec_b[i];
    const double gap = cs.ec_gap[i];
    if (gap > 0 && gap / std::min(m.block_size[a], m.block_size[b]) == ratio) {
      const std::int32_t n0 = m.block_first_node[a];
      const int ea = cs.ec_key[i] / 6;
      const double s = cs.ec_s[i];
      cs.max_pen_at = {-1, -1, a, b, (1 - s) * m.x[n0 + kTetEdges[ea][0]] + s * m.x[n0 + kTetEdges[ea][1]], true};
      return;
    }
  }
}

void edge_contact_forces(Model& m, ContactSet& cs, double dt, std::int64_t& active, double& pen_ratio) {
  const auto nbp = static_cast<std::int64_t>(cs.bp_a.size());
  const double zeta = cs.cfg.damping_ratio;
  cs.ec_matched.assign(cs.ec_a.size(), 0);
  // the previous contacts of each block pair: [bp_prev[j], bp_prev[j] + bp_prev_n[j]) are those
  // of bp j's blocks (both lists sorted by block pair; bp_prev_n 0 for a pair without any).
  // Found per block pair of the contacts (a few thousand) by a search of the pairs, not by a
  // walk over every pair; the counts set at the last step are cleared first.
  {
    for (const std::int32_t j : cs.bp_prev_set) cs.bp_prev_n[j] = 0;
    cs.bp_prev_set.clear();
    const std::size_t nq = cs.ec_a.size();
    for (std::size_t q = 0; q < nq;) {
      const std::int32_t a = cs.ec_a[q], b = cs.ec_b[q];
      std::size_t e = q + 1;
      while (e < nq && cs.ec_a[e] == a && cs.ec_b[e] == b) ++e;
      const auto first = std::lower_bound(cs.bp_a.begin(), cs.bp_a.end(), a);
      const auto last = std::upper_bound(first, cs.bp_a.end(), a);
      const auto lo = cs.bp_b.begin() + (first - cs.bp_a.begin()), hi = cs.bp_b.begin() + (last - cs.bp_a.begin());
      const auto it = std::lower_bound(lo, hi, b);
      if (it != hi && *it == b) {  // (else a rebuild dropped the pair: its contacts are closed below)
        const auto j = static_cast<std::int32_t>(it - cs.bp_b.begin());
        cs.bp_prev[j] = static_cast<std::int64_t>(q);
        cs.bp_prev_n[j] = static_cast<std::int32_t>(e - q);
        cs.bp_prev_set.push_back(j);
      }
      q = e;
    }
  }
  // (0) per block its drift bounds (blk_drift: the path length of its fastest node, contact.cpp;
  // the second +inf when its tolerance reach is over the cap): those of the node pairs' step when
  // the block is one of theirs (cb_drift, contact.cpp), else from its geometry, computed here
  // (eb_need 2: it has it). Its bounding sphere (the first test of an awake pair) is in its
  // geometry, computed only for the blocks of awake pairs.
  const auto neb = static_cast<std::int64_t>(cs.eb_block.size());
  static LoopSplit split_drift;
  split_drift.run(neb, [&](const LoopSplit::Range& part) {
    for (std::int64_t i = part.lo; i < part.hi; ++i) {
      const std::int32_t b = cs.eb_block[i];
      const std::int32_t slot = cs.block_slot[b];
      cs.eb_need[i] = slot < 0 ? 2 : 0;
      if (slot >= 0) {
        cs.eb_drift[2 * i] = cs.cb_drift[2 * slot];
        cs.eb_drift[2 * i + 1] = cs.cb_drift[2 * slot + 1];
        continue;
      }
      tet_geom(m, cs, b, cs.eb_geom[i]);
      const double d = cs.blk_drift[b];
      cs.eb_drift[2 * i] = d;
      cs.eb_drift[2 * i + 1] = cs.eb_geom[i].rho <= kContactRhoCap * cs.eb_geom[i].tol
                                   ? d
                                   : std::numeric_limits<double>::infinity();
    }
  });
  // the pairs awake this step (below) need their blocks' geometry: each computed once
  const bool sleep = cs.cfg.sleep;
  auto asleep = [&](std::int64_t j) {
    return sleep && cs.bp_prev_n[j] == 0 &&
           cs.eb_drift[2 * cs.bp_ia[j] + 1] + cs.eb_drift[2 * cs.bp_ib[j] + 1] < cs.bp_wake[j];
  };
  // (in parallel: a block's mark goes from 0 to 1 only, whichever pair sets it, and a 2 stays)
  std::uint8_t* const need = cs.eb_need.data();
  auto mark = [need](std::int32_t i) {
    std::uint8_t v;
#pragma omp atomic read relaxed
    v = need[i];
    if (v == 0) {
#pragma omp atomic write relaxed
      need[i] = 1;
    }
  };
  // the awake block pairs in order (the count pass below runs over them alone, their blocks'
  // geometry prefetched: 2 x 10 cache lines scattered over the blocks, most of its time): each
  // thread lists those of its range at the range's start in a scratch array, then copies them to
  // its offset (the counts of the threads before it), so the list is in pair order for any
  // thread count (the counts sized at the last build; the thread count may have grown since, as
  // for the node pairs' near list, contact.cpp)
  if (const auto want = static_cast<std::size_t>(omp_get_max_threads()) + 1; cs.bp_awake_count.size() < want)
    cs.bp_awake_count.assign(want, 0);
  static LoopSplit split_awake;
  std::int32_t* const awake_scratch = cs.bp_scratch.data();
#pragma omp parallel
  {
    const LoopSplit::Range part = split_awake.begin(nbp);
    std::int64_t n = 0;
    for (std::int64_t j = part.lo; j < part.hi; ++j) {
      if (asleep(j)) continue;
      awake_scratch[part.lo + n++] = static_cast<std::int32_t>(j);
      mark(cs.bp_ia[j]);
      mark(cs.bp_ib[j]);
    }
    split_awake.end(part);
    cs.bp_awake_count[part.thread + 1] = n;
#pragma omp barrier
#pragma omp single
    {
      cs.bp_awake_count[0] = 0;
      for (int k = 0; k < part.threads; ++k) cs.bp_awake_count[k + 1] += cs.bp_awake_count[k];
      cs.bp_awake.resize(static_cast<std::size_t>(cs.bp_awake_count[part.threads]));  // (within its capacity)
    }
    std::copy(awake_scratch + part.lo, awake_scratch + part.lo + n, cs.bp_awake.data() + cs.bp_awake_count[part.thread]);
  }
  split_awake.update();
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < neb; ++i)
    if (cs.eb_need[i] == 1) tet_geom(m, cs, cs.eb_block[i], cs.eb_geom[i]);
  // (1) count per block pair: the edge pairs in contact now, or in contact at the last step
  // (their last step is booked).
  // The sleep of far block pairs (as for the node pairs, contact.cpp): with dD_a, dD_b bounds on
  // how far any node of a, b has moved since a test that found the pair apart,
  // - apart by the bounding spheres by delta: the gap |c_a - c_b| - r_a - r_b shrinks by at most
  //   3 (dD_a + dD_b) (a centroid moves at most dD, a radius grows at most 2 dD);
  // - separated by a face plane of one of them by delta (the other's nodes in front of it): the
  //   blocks are at least delta apart, their points convex combinations of their nodes, so at
  //   least delta - dD_a - dD_b apart later. An edge contact needs a point of a's edge within
  //   tol of b's every face plane (and the other way round): within b's tolerance reach of b,
  //   at most kContactRhoCap tol_b while b's drift bound is finite (and a block is behind its own
  //   face planes only while it is not inverted: both reaches within the cap when tested).
  // So the pair is not tested again before dD_a + dD_b reaches delta / 3, or delta -
  // (kContactRhoCap + 1) max(tol_a, tol_b) (one tol for rounding): no contact is missed, the
  // results are the same bit for bit. Pairs that held contacts are tested every step.
  // (bp_count: per awake pair, by its place in the awake list; an asleep pair holds no contact
  // of the last step, so it has none now)
  const auto nawake = static_cast<std::int64_t>(cs.bp_awake.size());
  cs.bp_count[0] = 0;
  static LoopSplit split_count;
  split_count.run(nawake, [&](const LoopSplit::Range& part) {
    for (std::int64_t w = part.lo; w < part.hi; ++w) {
      if (w + kPrefetchAhead < nawake) {
        const std::int32_t ja = cs.bp_awake[w + kPrefetchAhead];
        prefetch_object(cs.eb_geom[cs.bp_ia[ja]]);
        prefetch_object(cs.eb_geom[cs.bp_ib[ja]]);
      }
      const std::int64_t j = cs.bp_awake[w];
      const std::int32_t ia = cs.bp_ia[j], ib = cs.bp_ib[j];
      const std::int64_t plo = cs.bp_prev[j], phi = plo + cs.bp_prev_n[j];
      const double drift_min = cs.eb_drift[2 * ia] + cs.eb_drift[2 * ib];
      const TetGeom& A = cs.eb_geom[ia];
      const TetGeom& B = cs.eb_geom[ib];
      const Vec3 ca = A.c, cb = B.c;
      const double ra = A.r, rb = B.r;
      const double dc2 = dot(ca - cb, ca - cb);
      bool near = dc2 <= (ra + rb) * (ra + rb);
      if (!near && plo == phi) {  // (most pairs: blocks apart; the longer of the two sleeps)
        double delta = (std::sqrt(dc2) - (ra + rb)) / 3.0, gap = 0;
        int unused = 0;
        if (A.rho <= kContactRhoCap * A.tol && B.rho <= kContactRhoCap * B.tol &&
            (separated(A, B, unused, gap) || separated(B, A, unused, gap)))
          delta = std::max(delta, gap - (kContactRhoCap + 1) * std::max(A.tol, B.tol));
        cs.bp_wake[j] = drift_min + delta;
        cs.bp_count[w + 1] = 0;
        continue;
      }
      int a_in = 0, b_in = 0;  // the edges of A that may reach into B, of B into A
      double gap = 0;
      const bool apart = near && (separated(A, B, b_in, gap) || separated(B, A, a_in, gap));
      near = near && (A.cand_edges != 0) && (B.cand_edges != 0) && !apart;
      if (apart && plo == phi && A.rho <= kContactRhoCap * A.tol && B.rho <= kContactRhoCap * B.tol)
        cs.bp_wake[j] = drift_min + (gap - (kContactRhoCap + 1) * std::max(A.tol, B.tol));
      if (!near && plo == phi) {  // (most of the rest: blocks side by side across a crack)
        cs.bp_count[w + 1] = 0;
        continue;
      }
      const int ma = A.cand_edges & a_in, mb = B.cand_edges & b_in;
      std::uint64_t hits = 0;
      const std::uint64_t maybe = near ? edge_candidates(A, ma, B, mb) : 0;
      // the candidates' full test, both roles (the edge pair in contact either way round is one
      // contact: A's edge into B or B's into A); a contact now or at the last step is one entry
      for (std::uint64_t left = maybe; left != 0; left &= left - 1) {
        const int key = std::countr_zero(left);
        EdgeHit h;
        if (edge_hit_either(A, key / 6, B, key % 6, h) != 0) hits |= std::uint64_t{1} << key;
      }
      cs.bp_count[w + 1] = std::popcount(hits | prev_keys(cs, plo, phi));
      // (and for the fill pass, what it would find again: whether the blocks are near, and their
      // edges that may reach into each other)
      cs.bp_hits[j] = hits | (near ? (std::uint64_t{1} << kHitsNear) | static_cast<std::uint64_t>(ma) << kHitsMaskA |
                                         static_cast<std::uint64_t>(mb) << kHitsMaskB
                                   : 0);
    }
  });
  cs.block_pair_tests += nawake;  // (every awake block pair is tested)
  for (std::int64_t w = 0; w < nawake; ++w) cs.bp_count[w + 1] += cs.bp_count[w];
  const auto nec = static_cast<std::size_t>(cs.bp_count[nawake]);
  for_each_edge_array(cs, [&](auto&, auto& now) { now.resize(nec); });
  // (2) the same tests again, now writing each contact at its offset with its force and energy
  static LoopSplit split_fill;
  const LoopSplit::CountMax touched = split_fill.run_reduce(nawake, LoopSplit::CountMax{}, [&](const LoopSplit::Range& part) {
    LoopSplit::CountMax held;
    for (std::int64_t w = part.lo; w < part.hi; ++w) {
      if (cs.bp_count[w + 1] == cs.bp_count[w]) continue;  // nothing here
      const std::int64_t j = cs.bp_awake[w];
      const std::int32_t a = cs.bp_a[j], b = cs.bp_b[j];
      const TetGeom& A = cs.eb_geom[cs.bp_ia[j]];
      const TetGeom& B = cs.eb_geom[cs.bp_ib[j]];
      const std::int64_t plo = cs.bp_prev[j], phi = plo + cs.bp_prev_n[j];
      auto o = static_cast<std::size_t>(cs.bp_count[w]);
      // (the count pass's findings: the edge pairs touching, the blocks near, each one's edges
      // that may reach the other)
      const std::uint64_t found = cs.bp_hits[j];
      const bool near = found >> kHitsNear & 1;
      const int ma = static_cast<int>(found >> kHitsMaskA & 63), mb = static_cast<int>(found >> kHitsMaskB & 63);
      const std::uint64_t hit_keys = found & ((std::uint64_t{1} << kHitsMaskA) - 1);
      int ignored = -1;  // (holds_ignored_overlap either way, looked up at the first need)
      // the edge pairs touching now or in contact at the last step, in key order (6 ea + eb)
      for (std::uint64_t left = hit_keys | prev_keys(cs, plo, phi); left != 0; left &= left - 1) {
        const std::int32_t key = std::countr_zero(left);
        const int ea = key / 6, eb = key % 6;
        const bool cand = (ma >> ea & 1) && (mb >> eb & 1);
        EdgeHit h;
        // the same test as the count pass's, where that found a hit (the others found none)
        const int role = near && cand && (hit_keys >> key & 1) ? edge_hit_either(A, ea, B, eb, h) : 0;
        const bool hit = role != 0;
        // the edge pushed along +n is a's (else b's); without a hit, a's unless both roles were
        // tried (which side a kept contact's weights are read from)
        const bool a_pushed = role == 1 || !(near && cand);
        const std::int64_t q = find_prev(cs, plo, phi, key);
        if (!hit && q < 0) continue;
        if (q >= 0) cs.ec_matched[q] = 1;
        // the edge pair's two edges as P (pushed along +n) and Q, with the weights of their nodes
        const TetGeom& P = a_pushed ? A : B;
        const TetGeom& Q = a_pushed ? B : A;
        const int ep = a_pushed ? ea : eb, eq = a_pushed ? eb : ea;
        const double s = hit ? h.s : (q >= 0 ? (a_pushed ? cs.ec_s[q] : cs.ec_t[q]) : 0.5);
        const double t = hit ? h.t : (q >= 0 ? (a_pushed ? cs.ec_t[q] : cs.ec_s[q]) : 0.5);
        const Vec3 vp = (1 - s) * P.v[kTetEdges[ep][0]] + s * P.v[kTetEdges[ep][1]];
        const Vec3 vq = (1 - t) * Q.v[kTetEdges[eq][0]] + t * Q.v[kTetEdges[eq][1]];
        const Vec3 du = dt * (vp - vq);  // relative displacement of P's point over the last step
        // stiffness and mass: the smallest of the four nodes'
        const std::int32_t np0 = m.block_first_node[a_pushed ? a : b], nq0 = m.block_first_node[a_pushed ? b : a];
        const std::int32_t nodes[4] = {np0 + kTetEdges[ep][0], np0 + kTetEdges[ep][1],
                                       nq0 + kTetEdges[eq][0], nq0 + kTetEdges[eq][1]};
        double k = cs.kc[nodes[0]], mass = m.mass[nodes[0]];
        for (int i = 1; i < 4; ++i) k = std::min(k, cs.kc[nodes[i]]), mass = std::min(mass, m.mass[nodes[i]]);
        k *= kEdgeShare;
        // the force on a's edge last step (stored with a as the reference side)
        const Vec3 fa_old = q >= 0 ? cs.ec_force[q] : Vec3{};
        const Vec3 fp_old = a_pushed ? fa_old : -1.0 * fa_old;
        const double gap_old = q >= 0 ? cs.ec_gap[q] : 0.0;
        const double k_old = q >= 0 ? cs.ec_k[q] : k;
        const Vec3 fta_old = q >= 0 ? cs.ec_ft[q] : Vec3{};  // tangential part, on a's edge
        const Vec3 ftp_old = a_pushed ? fta_old : -1.0 * fta_old;
        const double kt_old = cs.shear_ratio * k_old;
        const double e_old = 0.5 * k_old * gap_old * gap_old +
                             (kt_old > 0 ? 0.5 * dot(ftp_old, ftp_old) / kt_old : 0.0);
        double d0 = q >= 0 ? cs.ec_d0[q] : 0.0;
        Vec3 fp{}, ftp{};
        double gap = 0;
        const double kt = cs.shear_ratio * k;
        // A crossing first seen deeper than two steps' approach is no touch this contact can
        // resolve (blocks that overlap by a good part of their size, after crushing near a
        // charge): it is left to the node-to-face contacts. Taken up with its depth ignored, such
        // a crossing lost its ignored depth each time its gap came to zero and was taken up anew
        // the next step, pushing a step's approach back at once: -2.1 MJ of energy from nothing
        // by 5.4 ms in the coarse SPEC 5.3 cylinder, scheme B (docs/verification_contact.md).
        // (the depth d = (x_q - x_p) . n grows at the rate -vn: the approach is max(0, -vn); an
        // edge pair moving apart has no approach, and its depth none of this step's)
        const double approach = std::max(0.0, -dot(vp - vq, h.n));
        const bool deep_new = hit && q < 0 && h.d > 2.0 * approach * dt + std::min(P.tol, Q.tol);
        if (hit && !deep_new) {
          const double vn = dot(vp - vq, h.n);
          // at first touch, depth beyond one step's approach is ignored (d0): an edge crossing is
          // found in the step it happens, and a larger allowance would push the rest back at
          // once (energy from nothing). Moving apart, the whole depth: two bodies that overlap and
          // part show crossings of small depth as the overlap closes, never approached (the
          // deep touch test of test_contact.cpp gained 4.5 % of its energy with |vn| here).
          // Inside an overlap the node contacts ignore (a node of one block holds a contact in
          // the other's body with an ignored depth), a crossing not pressing yet ignores its
          // depth too: as two bodies that overlap part or close, the edges of one sweep through
          // the other's, each a new crossing approached this step, and pushing that back held
          // them together (-10 % of the kinetic energy as two overlapping cubes parted, the
          // deep-touch test of test_contact.cpp).
          if ((q < 0 || gap_old == 0) && ignored < 0)
            ignored = holds_ignored_overlap(m, cs, a, b) || holds_ignored_overlap(m, cs, b, a);
          if (q < 0 || gap_old == 0) d0 = std::max(d0, ignored ? h.d : h.d - approach * dt);
          // in contact: the penetration grows at most by this step's approach; a jump of the
          // closest points or of the common normal (edges turning, the pushed edge changing) is
          // no motion and is not pushed back (a guard: in the runs measured it changed nothing)
          else
            d0 = std::max(d0, h.d - gap_old - approach * dt);
          d0 = std::max(0.0, std::min(d0, h.d));
          gap = h.d - d0;
          const double cdamp = zeta > 0 ? 2.0 * zeta * std::sqrt(k * mass) : 0.0;
          const double fn = gap > 0 ? std::max(0.0, k * gap - cdamp * vn) : 0.0;
          if (gap > 0) {
            // Coulomb friction, as for the node pairs: the tangential spring turned into the
            // current tangent plane (magnitude kept), incremented by -k_t du_t, capped at mu F_n
            const double mu = cs.mu[static_cast<std::size_t>(m.block_region[a]) * cs.nreg + m.block_region[b]];
            ftp = ftp_old;
            const double f2 = dot(ftp, ftp);
            ftp -= dot(ftp, h.n) * h.n;
            const double fp2 = dot(ftp, ftp);
            if (fp2 > 0) ftp *= std::sqrt(f2 / fp2);
            const Vec3 du_t = du - dot(du, h.n) * h.n;
            ftp -= kt * du_t;
            const double cap = mu * fn, mag = norm(ftp);
            if (mag > cap) ftp *= (cap > 0 ? cap / mag : 0.0);
          }
          fp = fn * h.n + ftp;
          if (gap > 0) {
            ++held.count;
            held.max = std::max(held.max, gap / std::min(m.block_size[a], m.block_size[b]));
          }
        } else {
          d0 = 0;
        }
        const double e_new = 0.5 * k * gap * gap + (kt > 0 ? 0.5 * dot(ftp, ftp) / kt : 0.0);
        cs.ecn_diss[o] = (q >= 0 ? cs.ec_diss[q] : 0.0) - 0.5 * dot(fp_old + fp, du) - (e_new - e_old);
        cs.ecn_a[o] = a;
        cs.ecn_b[o] = b;
        cs.ecn_key[o] = key;
        cs.ecn_d0[o] = d0;
        cs.ecn_gap[o] = gap;
        cs.ecn_k[o] = k;
        cs.ecn_force[o] = a_pushed ? fp : -1.0 * fp;
        cs.ecn_ft[o] = a_pushed ? ftp : -1.0 * ftp;
        cs.ecn_s[o] = a_pushed ? s : t;  // the weights on a's edge and on b's
        cs.ecn_t[o] = a_pushed ? t : s;
        ++o;
      }
    }
    return held;
  }, LoopSplit::CountMax::join);
  active += touched.count;
  pen_ratio = std::max(pen_ratio, touched.max);
  // contacts of the last step whose block pair is gone (a rebuild dropped it): their stored
  // energy and their dissipation so far go to the closed account
  for (std::size_t q = 0; q < cs.ec_a.size(); ++q)
    if (!cs.ec_matched[q])
      cs.ec_diss_closed += cs.ec_diss[q] + 0.5 * cs.ec_k[q] * cs.ec_gap[q] * cs.ec_gap[q] +
                           0.5 * dot(cs.ec_ft[q], cs.ec_ft[q]) / (cs.shear_ratio * cs.ec_k[q]);
  // (3) the forces, gathered in list order: a's edge (1 - s, s), b's edge -(1 - t, t)
  for (std::size_t i = 0; i < nec; ++i) {
    const Vec3 F = cs.ecn_force[i];
    if (F.x == 0 && F.y == 0 && F.z == 0) continue;
    const int ea = cs.ecn_key[i] / 6, eb = cs.ecn_key[i] % 6;
    const std::int32_t na = m.block_first_node[cs.ecn_a[i]], nb = m.block_first_node[cs.ecn_b[i]];
    const double s = cs.ecn_s[i], t = cs.ecn_t[i];
    m.f[na + kTetEdges[ea][0]] += (1 - s) * F;
    m.f[na + kTetEdges[ea][1]] += s * F;
    m.f[nb + kTetEdges[eb][0]] -= (1 - t) * F;
    m.f[nb + kTetEdges[eb][1]] -= t * F;
  }
  // keep only the contacts still holding something or in contact (the others ended this step)
  std::size_t w = 0;
  for (std::size_t i = 0; i < nec; ++i) {
    if (cs.ecn_gap[i] == 0) {
      cs.ec_diss_closed += cs.ecn_diss[i];
      continue;
    }
    for_each_edge_array(cs, [&](auto&, auto& now) { now[w] = now[i]; });
    ++w;
  }
  for_each_edge_array(cs, [&](auto& last, auto& now) {
    now.resize(w);
    last.swap(now);
  });
  cs.ec_active = static_cast<std::int64_t>(w);
  cs.ec_active_max = std::max(cs.ec_active_max, cs.ec_active);
}

}  // namespace cdem
