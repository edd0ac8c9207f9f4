// General contact, the per-step narrow phase (physics/contact.hpp): the nodes' drift and the
// rebuild trigger, the sleep of far pairs, the node-to-face forces, then the edge contacts
// (contact_edges.cpp) and the gathers. The set-up and accounts are in contact_set.cpp, the
// pairs' search in contact_broad_phase.cpp.
#include "cdem/physics/contact.hpp"
#include "cdem/physics/contact_passivity.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "cdem/core/loop_split.hpp"
#include "cdem/core/prefetch.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {

// The sleep of far pairs. With D_i the path length of node i since the first build or the
// checkpoint loaded (the sum of |v_i| dt), and B_b that of block b's fastest node (the sum of
// max_i |v_i| dt over b's nodes): since a test at t0 at which node n was found outside block b's
// grown bounding sphere by delta, |x_n - c| - (1.25 R + 2 tol) has shrunk by at most
// dD_n + 3.5 dD_b, with dD_b = max over b's nodes of D_i(t) - D_i(t0) <= B_b(t) - B_b(t0): n
// moved at most dD_n, the centroid c (a mean of b's nodes) at most dD_b, and the radius R (the
// farthest node from c) grew by at most 2 dD_b, the reach by 1.25 x that. So the pair is not
// tested again until D_n(t) + 3.5 B_b(t) reaches D_n(t0) + 3.5 B_b(t0) + delta: it could not be
// found near before (the same pairs are near, bit for bit), and a slow node beside a slow block
// sleeps however fast other fragments fly.
constexpr double kSleepRate = 3.5;
//
// The same sleep for a pair found inside that sphere but in front of a face plane (a node at a
// neighbour's corner across a crack: 86 % of the pairs tested each step in the late SPEC 5.3
// cylinder were of this kind, 0.1 to 1 block size in front of a plane). For a simplex b (convex):
// every point of b is behind face plane k, so the node's distance to b is at least
// h = max_k g_k(x), the most it lies in front of a plane. The block's points are convex
// combinations of its nodes with fixed weights, so b(t) lies within dD_b of b(t0) (Hausdorff), and
// the node's distance to b(t) is at least h - dD_n - dD_b. A node that passes the test lies
// behind every plane offset by tol: in the simplex scaled about its incentre I by
// (1 + tol / r_in), at most rho = tol max_i |a_i - I| / r_in from b (the block's tolerance reach,
// contact.hpp). So with rho <= kContactRhoCap tol, the pair cannot pass before dD_n + dD_b
// reaches h - (kContactRhoCap + 1) tol (one tol more for rounding), which the wake bound above
// implies (dD_b <= kSleepRate dD_b). A block whose rho exceeds the cap this step (a
// sliver, an inverted or a flat block, a quad) has all its pairs tested.

// A pair is not in contact once the node's projection is this far outside its contact face, in
// barycentric coordinates (half the face: a node at a face's corner, or just past it, still is).
constexpr double kOffFace = 0.5;

// (passivity: contact_passivity.hpp)

void contact_forces(Model& m, ContactSet& cs, double dt) {
  if (!cs.enabled) return;
  // Rebuild when a candidate node has moved more than half its skin, or when points were released
  // (their faces become candidates) once the nodes may have moved towards each other by
  // kReleaseDrift x skin since the release: at most 2 max|v| dt per step. Until then no node
  // can have come nearer a released face than that, so a contact found late overlaps it by at
  // most this (10 % of the skin); a breaking model releases points nearly every step, and a
  // rebuild at each cost most of its step.
  constexpr double kReleaseDrift = 0.1;
  // A node farther than this x skin from a block at the step its points are released reaches its
  // faces only after 2 max|v| dt has summed past it: the nearer ones decide the rebuild
  // (contact_release.cpp).
  constexpr double kReleaseFar = 2.0;
  // The nodes' motion this step, in one pass over the nodes that can take part in contact (a
  // solid charge's explosive blocks are left out: their products, often the fastest nodes, would
  // trigger rebuilds for nothing): each node's path length since the build (the bound on how far
  // it has moved, for the sleep) and the largest speed. A rebuild below starts both from 0 again.
  const bool first_build = cs.released_seen < 0;
  const bool release_pending = !first_build && cs.released_seen != m.released_points;
  double vmax = 0;
  if (release_pending || !cs.pair_node.empty()) {
    const auto nbk = static_cast<std::int64_t>(m.n_blocks());
    const auto ngrp = static_cast<std::int64_t>(cs.grp_speed.size());
    const std::uint8_t* const skip = m.no_contact.empty() ? nullptr : m.no_contact.data();
    static LoopSplit split_speed;
    const bool boxes = release_pending && cs.grp_lo.size() == static_cast<std::size_t>(ngrp);
    vmax = split_speed.run_reduce(ngrp, 0.0, [&](const LoopSplit::Range& part) {
      double v_top = 0;
      constexpr double inf = std::numeric_limits<double>::infinity();
      for (std::int64_t g = part.lo; g < part.hi; ++g) {
        double vg = 0;  // (the group's largest speed: the sleep's local clocks, below)
        Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};  // (its box: the release trigger's)
        for (std::int64_t b = g * kSleepGroup; b < std::min(nbk, (g + 1) * kSleepGroup); ++b) {
          if (skip && skip[b]) continue;
          double vb = 0;  // (the block's fastest node)
          for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
            const double vn = std::sqrt(dot(m.v[n], m.v[n]));
            cs.node_drift[n] += vn * dt;
            vb = std::max(vb, vn);
            if (boxes)
              for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], m.x[n][d]), hi[d] = std::max(hi[d], m.x[n][d]);
          }
          cs.blk_drift[b] += vb * dt;
          vg = std::max(vg, vb);
        }
        cs.grp_speed[g] = vg;
        if (boxes) cs.grp_lo[g] = lo, cs.grp_hi[g] = hi;
        v_top = std::max(v_top, vg);
      }
      return v_top;
    }, [](double x, double y) { return std::max(x, y); });
  }
  bool due = first_build || cs.rebuild_due;
  if (release_pending) {
    const double vnear = release_near_speed(m, cs, kReleaseFar * cs.skin);
    cs.release_drift += 2.0 * vnear * dt;
    cs.release_drift_far += 2.0 * vmax * dt;
    due = cs.release_drift > kReleaseDrift * cs.skin || cs.release_drift_far > (kReleaseDrift + kReleaseFar) * cs.skin;
  }
  if (!due) {
    // (the candidate nodes, then the candidate blocks' other nodes)
    auto moved = [&](const std::vector<std::int32_t>& nodes, const std::vector<Vec3>& x0,
                     const std::vector<double>& lim2) {
      const auto nn = static_cast<std::int64_t>(nodes.size());
      int any = 0;
#pragma omp parallel for schedule(static) reduction(| : any)
      for (std::int64_t j = 0; j < nn; ++j) {
        const Vec3 d = m.x[nodes[j]] - x0[j];
        any |= dot(d, d) > lim2[j];
      }
      return any != 0;
    };
    due = moved(cs.cand_nodes, cs.x_build, cs.cand_lim2) || moved(cs.watch_nodes, cs.watch_x, cs.watch_lim2);
  }
  if (due) rebuild_contact_pairs(m, cs, dt);
  // The groups' clocks: each grows by the largest |v| dt of its own nodes and of its pairs'
  // blocks (the groups listed at the rebuild: those of every pair now), whether or not the pairs
  // were rebuilt (the pairs that stay keep their wakes, contact_broad_phase.cpp).
  {
    const auto ngrp = static_cast<std::int64_t>(cs.grp_clock.size());
    static LoopSplit split_clock;
    split_clock.run(ngrp, [&](const LoopSplit::Range& part) {
      for (std::int64_t g = part.lo; g < part.hi; ++g) {
        double v = 0;
        for (auto i = cs.grp_nbr_start[g]; i < cs.grp_nbr_start[g + 1]; ++i) v = std::max(v, cs.grp_speed[cs.grp_nbr[i]]);
        cs.grp_clock[g] += v * dt;
      }
    });
  }
  const auto npair = static_cast<std::int64_t>(cs.pair_node.size());
  if (npair == 0) {
    std::int64_t none = 0;
    double pen = 0;
    if (cs.edges) edge_contact_forces(m, cs, dt, none, pen);  // (closes what the edges held)
    cs.active = none;
    return;
  }
  const double zeta = cs.cfg.damping_ratio;
  std::int64_t active = 0;
  double pen_ratio = 0;
  // (a) Quick reject. A pair that held no contact at the last step and whose node lies outside
  // the block's bounding sphere (centroid c, radius R) grown by 0.25 R + 2 tol cannot be behind
  // every face within tol (the faces offset by tol stay inside that sphere unless a dihedral
  // angle of the block is below ~0.2 degrees): it takes no force and changes no state but its
  // ignored depth and inside flag (both 0 outside the block). Most candidate pairs of a
  // fragmented model are of this kind (a node sees ~10 blocks within its grown boxes; 315 000
  // pairs and 184 contacts in the SPEC 5.3 cylinder at 4 ms), so the pairs that pass ("near")
  // are listed, in pair order, and only they are worked on below.
  const auto ncb = static_cast<std::int64_t>(cs.cblock.size());
  // (the blocks' drift bounds for the sleep, in a loop of their own: in the loop below the
  // compiler would round the geometry differently, and the reject would then differ in the last
  // bit at planes through a node)
  // A block's bound is the path length of its fastest node (blk_drift): every node of it has
  // moved at most its growth since a test. Until 7 Dec 2026 it was the spread of its nodes' own
  // path lengths, max_i D_i(t) - min_i D_i(t0): also a bound, but one whose slack the nodes'
  // different paths (a block turning and vibrating) eat over a long run, never given back until a
  // restart reset the path lengths. Late in the coarse SPEC 5.3 scheme A, contact cost 6.6 ms per
  // step in the run and 3.6 ms after a restart at the same state (docs/performance.md). Either
  // bound lets no near pair sleep: the same pairs are near, the results the same bits.
  static LoopSplit split_drift;
  split_drift.run(ncb, [&](const LoopSplit::Range& part) {
    for (std::int64_t j = part.lo; j < part.hi; ++j) {
      const double d = cs.blk_drift[cs.cblock[j]];
      cs.cb_drift[2 * j] = d;
      cs.cb_drift[2 * j + 1] = d;
    }
  });
  // (a block whose tolerance reach exceeds the cap wakes all its pairs this step: its largest
  // drift bound +inf, flagged here while its geometry is at hand; rare: a sliver, a block crushed
  // flat or inverted)
  static LoopSplit split_planes;
  const int over_cap = split_planes.run_reduce(ncb, 0, [&](const LoopSplit::Range& part) {
    int over = 0;
    for (std::int64_t j = part.lo; j < part.hi; ++j) {
      const std::int32_t b = cs.cblock[j], n0 = m.block_first_node[b];
      const int nbn = m.block_first_node[b + 1] - n0;
      BlockPlanes& bp = cs.cb_geom[j];
      Vec3 c{};
      for (int i = 0; i < nbn; ++i) c += m.x[n0 + i];
      c *= 1.0 / nbn;
      double r2 = 0;
      for (int i = 0; i < nbn; ++i) {
        const Vec3 d = m.x[n0 + i] - c;
        r2 = std::max(r2, dot(d, d));
      }
      // (a node exactly on a face's plane or an edge, as where aligned blocks land corner on
      // corner, counts as inside: vibration moves it by ~strain x size either way)
      bp.tol = 1e-3 * m.block_size[b];
      const double reach = 1.25 * std::sqrt(r2) + 2 * bp.tol;
      bp.c = c;
      bp.reach2 = reach * reach;
      // the planes of its faces: a point and the outward unit normal
      const LocalFaces lf = local_faces(m.block_type[b]);
      bp.nf = lf.count;
      for (int k = 0; k < lf.count; ++k) {
        const Vec3 a0 = m.x[n0 + lf.f[k][0]], a1 = m.x[n0 + lf.f[k][1]];
        bp.a0[k] = a0;
        if (lf.nodes_per_face == 3) {
          bp.n[k] = normalized(cross(a1 - a0, m.x[n0 + lf.f[k][2]] - a0));
        } else {
          const Vec3 t = a1 - a0;
          bp.n[k] = normalized(Vec3{t.y, -t.x, 0.0});
        }
      }
      bp.rho = simplex_tolerance_reach(m.block_type[b], &m.x[n0], bp.a0, bp.n, bp.tol);
      if (!(bp.rho <= kContactRhoCap * bp.tol)) {
        cs.cb_drift[2 * j + 1] = std::numeric_limits<double>::infinity();
        over = 1;
      }
    }
    return over;
  }, [](int x, int y) { return x | y; });
  if (over_cap)
    for (std::int64_t j = 0; j < ncb; ++j)
      if (cs.cb_drift[2 * j + 1] == std::numeric_limits<double>::infinity())
        for (auto i = cs.cb_pair_start[j]; i < cs.cb_pair_start[j + 1]; ++i) {
          cs.pair_gwake[cs.cb_pair[i]] = -1.0f;
        }
  // The near list: each thread lists the near pairs of a contiguous range of pairs at the start
  // of that range in a scratch array, then copies them to its offset, so the list is in pair
  // order for any thread count. (The counts are sized for the thread count at the last build; a
  // run's thread count may have grown since: thread_governor.hpp, or bench's 2-thread loop from
  // a 1-thread set-up.)
  if (const auto want = static_cast<std::size_t>(omp_get_max_threads()) + 1; cs.near_count.size() < want)
    cs.near_count.assign(want, 0);
  // A pair asleep by the test above with slack S (its wake bound less D_n + kSleepRate max_i D_i
  // now) cannot wake before its node's group clock has grown by S / (1 + kSleepRate): the path
  // length of its node and of each node of its block grows by at most that clock's increment.
  // So it is not looked at until then (one load instead of the node's and the block's drift
  // bounds, the clock read once per group). A near pair is looked at every step. (0.999: the
  // path lengths are sums rounded differently.) Until 4 Dec 2026 the clock was one for all, the
  // fastest node's path anywhere: in the late SPEC 5.3 cylinder a pair woke every ~11 steps on
  // it, though its own bound held, as fragments flew at 165 m/s elsewhere.
  const double* const clock = cs.grp_clock.data();
  const std::int32_t* const gstart = cs.grp_pair_start.data();
  const auto ngrp = static_cast<std::int32_t>(cs.grp_clock.size());
  const bool sleep = cs.cfg.sleep;
  // (the arrays through local pointers: a store to a byte array may alias anything, and the
  // compiler reloaded every vector's data pointer after each)
  const std::int8_t* const kf_ = cs.pair_kf.data();
  const std::int32_t *const node_ = cs.pair_node.data(), *const cb_ = cs.pair_cb.data();
  const double *const drift = cs.node_drift.data(), *const cbd = cs.cb_drift.data();
  const BlockPlanes* const geom = cs.cb_geom.data();
  float* const gwake = cs.pair_gwake.data();
  double *const pwake = cs.pair_wake.data(), *const g0 = cs.pair_g0.data();
  std::int32_t* const scratch = cs.near_scratch.data();
  const Vec3* const x_ = m.x.data();
  static LoopSplit split_near;
  // (begin and end by hand: the thread's time is its pass, not the wait at the barrier after it)
#pragma omp parallel
  {
    const LoopSplit::Range part = split_near.begin(npair);
    const std::int64_t t = part.thread, nt = part.threads;
    const std::int64_t lo = part.lo, hi = part.hi;
    // 1. The pairs awake this step (most pairs are asleep on their group's clock), listed at the start of
    // the range without a branch: a streaming pass of one byte and one float per pair.
    std::int64_t nawake = 0;
    // (the group of the range's first pair: the last whose pairs start at or before it)
    const std::int32_t g_lo = static_cast<std::int32_t>(std::upper_bound(gstart, gstart + ngrp + 1, lo) - gstart) - 1;
    for (std::int32_t g = std::max(g_lo, 0); g < ngrp && gstart[g] < hi; ++g) {
      const double c = clock[g];
      for (std::int64_t p = std::max<std::int64_t>(lo, gstart[g]); p < std::min<std::int64_t>(hi, gstart[g + 1]); ++p) {
        scratch[lo + nawake] = static_cast<std::int32_t>(p);
        nawake += (kf_[p] >= 0) | !(sleep && c < static_cast<double>(gwake[p]));
      }
    }
    std::int32_t g = std::max(g_lo, 0);  // (the awake pairs' group, walking up with them)
    // 2. The awake pairs, their scattered data prefetched a few pairs ahead (the block planes
    // above all: 4 cache lines per block, 2 MB for the late SPEC 5.3 state). The near ones are
    // written over the list's consumed head, in pair order.
    std::int64_t count = 0, tests = 0;
    for (std::int64_t i = 0; i < nawake; ++i) {
      if (i + kPrefetchAhead < nawake) {
        const std::int32_t pa = scratch[lo + i + kPrefetchAhead];
        prefetch_object(geom[cb_[pa]]);
        prefetch_at(static_cast<std::size_t>(node_[pa]), x_, drift);
        prefetch_at(static_cast<std::size_t>(pa), pwake);
      }
      const std::int64_t p = scratch[lo + i];
      bool near = kf_[p] >= 0;
      const std::int32_t n = node_[p], j = cb_[p];
      // (a pair found outside the sphere by delta sleeps until the drift bound has grown by
      // delta: it cannot have come near before, and it would only be found outside again)
      if (!near && (!sleep || drift[n] + kSleepRate * cbd[2 * j + 1] >= pwake[p])) {
        ++tests;
        const BlockPlanes& bp = geom[j];
        const Vec3 x = x_[n];
        const Vec3 dx = x - bp.c;
        const double d2 = dot(dx, dx);
        near = !(d2 > bp.reach2);
        if (!near) {
          pwake[p] = drift[n] + kSleepRate * cbd[2 * j] + (std::sqrt(d2) - std::sqrt(bp.reach2));
        } else {
          // in front of a face by more than tol: outside the block (the narrow phase's own test,
          // on the same planes, to the same bits)
          for (int k = 0; k < bp.nf && near; ++k) near = dot(x - bp.a0[k], bp.n[k]) <= bp.tol;
          if (!near && bp.rho <= kContactRhoCap * bp.tol) {  // (else the block wakes its pairs anyway)
            double h = -std::numeric_limits<double>::infinity();  // (how far in front)
            for (int k = 0; k < bp.nf; ++k) h = std::max(h, dot(x - bp.a0[k], bp.n[k]));
            pwake[p] = drift[n] + kSleepRate * cbd[2 * j] + (h - (kContactRhoCap + 1) * bp.tol);
          }
        }
        if (!near && g0[p] != 0) g0[p] = 0;  // outside: no ignored depth (d0)
      }
      const double slack = near ? -1.0 : pwake[p] - (drift[n] + kSleepRate * cbd[2 * j + 1]);
      // (rounded down to a float: the pair may wake a little early, never late)
      while (gstart[g + 1] <= p) ++g;
      const double wake = slack > 0 ? clock[g] + 0.999 * slack / (1 + kSleepRate) : -1.0;
      float wf = static_cast<float>(wake);
      if (static_cast<double>(wf) > wake) wf = std::nextafter(wf, -std::numeric_limits<float>::infinity());
      gwake[p] = wf;
      if (near) scratch[lo + count++] = static_cast<std::int32_t>(p);
    }
    split_near.end(part);
    cs.near_count[t + 1] = count;
#pragma omp atomic
    cs.pair_tests += tests;
#pragma omp barrier
#pragma omp single
    {
      cs.near_count[0] = 0;
      for (std::int64_t k = 0; k < nt; ++k) cs.near_count[k + 1] += cs.near_count[k];
      cs.near.resize(static_cast<std::size_t>(cs.near_count[nt]));  // within its capacity
    }
    // (each thread's near pairs, in order from the start of its range, to its offset: a copy
    // of the few near pairs, not a second pass over all of them)
    std::copy(scratch + lo, scratch + lo + count, cs.near.data() + cs.near_count[t]);
  }
  split_near.update();
  const auto nnear = static_cast<std::int64_t>(cs.near.size());
  cs.near_node.resize(static_cast<std::size_t>(nnear));  // (within their capacity)
  cs.near_forced.resize(static_cast<std::size_t>(nnear));
  cs.near_dd.resize(static_cast<std::size_t>(nnear));
  // (a') geometry of every near pair
  static LoopSplit split_geom;
  split_geom.run(nnear, [&](const LoopSplit::Range& part) {
    for (std::int64_t ii = part.lo; ii < part.hi; ++ii) {
      if (ii + 2 * kPrefetchAhead < nnear) {
        const auto q = static_cast<std::size_t>(cs.near[ii + 2 * kPrefetchAhead]);
        prefetch_at(q, cs.pair_node.data(), cs.pair_block.data(), cs.pair_cb.data(), cs.pair_kf.data());
        prefetch_for_write_at(q, cs.pair_g.data(), cs.pair_n.data(), cs.pair_kf_now.data(), cs.pair_off.data(),
                              cs.pair_margin.data(), cs.pair_score.data(), cs.pair_w.data());
      }
      if (ii + kPrefetchAhead < nnear) {
        const std::int32_t q = cs.near[ii + kPrefetchAhead], bq = cs.pair_block[q];
        prefetch_at(static_cast<std::size_t>(cs.pair_node[q]), m.x.data(), m.v.data());
        prefetch_at(static_cast<std::size_t>(m.block_first_node[bq]), m.v.data(), m.x.data());
        prefetch_object(cs.cb_geom[cs.pair_cb[q]]);
      }
      const std::int32_t p = cs.near[ii];
      const std::int32_t n = cs.pair_node[p], b = cs.pair_block[p];
      cs.near_node[ii] = n;
      const Vec3 x = m.x[n];
      // The node against every face of the block: inside when behind all of them; the contact
      // face is the nearest candidate face (largest g, the first of equals).
      const LocalFaces lf = local_faces(m.block_type[b]);
      const std::int32_t n0 = m.block_first_node[b];
      const BlockPlanes& bp = cs.cb_geom[cs.pair_cb[p]];
      const double tol = bp.tol;
      bool inside = true;
      double margin = std::numeric_limits<double>::infinity();
      double gk_all[4];
      Vec3 nk_all[4];
      double gprev[4], approach[4];
      for (int k = 0; k < lf.count; ++k) {
        // (the face plane of the step's block geometry: the same expressions, rounded as written
        // without multiply-add contraction, so the same bits as computing it here again)
        const Vec3 a0 = bp.a0[k], nk = bp.n[k];
        Vec3 vf = m.v[n0 + lf.f[k][0]] + m.v[n0 + lf.f[k][1]];
        if (lf.nodes_per_face == 3)
          vf = (1.0 / 3) * (vf + m.v[n0 + lf.f[k][2]]);
        else
          vf = 0.5 * vf;
        const double gk = dot(x - a0, nk);
        gk_all[k] = gk;
        nk_all[k] = nk;
        approach[k] = -dot(m.v[n] - vf, nk);        // how fast the node moves into the plane
        gprev[k] = gk + dt * approach[k];           // the gap a step ago (relative motion)
        inside = inside && gk <= tol;
        margin = std::min(margin, -gk);
      }
      // The contact face: the one the node is in contact with since an earlier step while it is
      // still behind it; else, of the candidate faces it is behind or on (within tol), the one with
      // the largest gap a step ago: the face it came in by (at an edge or a corner, not the one it
      // happens to be nearest to), and a node on a face's plane, in front of it, is not in contact
      // through the far side; else the nearest candidate face. In contact when behind that face.
      int kf = -1;
      const int kp = cs.pair_kf[p];
      if (kp >= 0 && kp < lf.count && cs.face_cand[4 * b + kp] && gk_all[kp] < 0) kf = kp;
      if (kf < 0) {  // behind or on (within tol) the plane: the face with the largest gap a step ago
        double best = -std::numeric_limits<double>::infinity();
        for (int k = 0; k < lf.count; ++k)
          if (cs.face_cand[4 * b + k] && gk_all[k] < tol && gprev[k] > best) best = gprev[k];
        // Faces whose gap a step ago is within tol of the largest are all ones the node may have
        // come in by (it was on their planes, within tol): of these, the one it moves into the
        // fastest. A node slowly sinking at a block's corner or edge lies on the side faces'
        // planes (g = 0 to rounding) while a step ago it was already a little behind the top face:
        // by the gap alone a side face won, the contact pushed sideways with no depth, and the
        // node sank unheld (the aligned stack of test_contact.cpp, corners on corners, whichever
        // way its last bits fell).
        double fastest = -std::numeric_limits<double>::infinity();
        for (int k = 0; k < lf.count; ++k)
          if (cs.face_cand[4 * b + k] && gk_all[k] < tol && gprev[k] >= best - tol && approach[k] > fastest)
            fastest = approach[k], kf = k;
      }
      if (kf < 0) {
        double best = -std::numeric_limits<double>::infinity();
        for (int k = 0; k < lf.count; ++k)
          if (cs.face_cand[4 * b + k] && gk_all[k] > best) best = gk_all[k], kf = k;
      }
      const double g = kf >= 0 ? gk_all[kf] : -std::numeric_limits<double>::infinity();
      const Vec3 nrm = kf >= 0 ? nk_all[kf] : Vec3{};
      // weights of the block's nodes: the projection onto face kf, barycentric, clamped; `lowest`
      // the smallest coordinate before clamping (< 0: the projection falls outside the face)
      std::array<double, 4> w{0, 0, 0, 0};
      double lowest = 1.0;
      if (kf >= 0) {
        const int c = lf.nodes_per_face;
        const std::array<int, 3>& fl = lf.f[kf];
        const Vec3 p0 = m.x[n0 + fl[0]];
        double wf[3] = {0, 0, 0};
        if (c == 3) {
          const Vec3 e1 = m.x[n0 + fl[1]] - p0, e2 = m.x[n0 + fl[2]] - p0, v2 = x - g * nrm - p0;
          const double d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2);
          const double d20 = dot(v2, e1), d21 = dot(v2, e2), den = d00 * d11 - d01 * d01;
          wf[1] = den > 0 ? (d11 * d20 - d01 * d21) / den : 1.0 / 3;
          wf[2] = den > 0 ? (d00 * d21 - d01 * d20) / den : 1.0 / 3;
          wf[0] = 1.0 - wf[1] - wf[2];
        } else {
          const Vec3 t = m.x[n0 + fl[1]] - p0;
          const double l2 = dot(t, t);
          wf[1] = l2 > 0 ? dot(x - p0, t) / l2 : 0.5;
          wf[0] = 1.0 - wf[1];
        }
        double sum = 0;
        for (int i = 0; i < c; ++i) lowest = std::min(lowest, wf[i]);
        for (int i = 0; i < c; ++i) sum += (wf[i] = std::max(0.0, wf[i]));
        for (int i = 0; i < c; ++i) w[fl[i]] = sum > 0 ? wf[i] / sum : 1.0 / c;
      }
      // A node whose projection falls far outside its contact face is not penetrating through
      // that face: it is inside a distorted quad whose face lines no longer bound it, or it slid
      // past the end of the face that held it. Its depth to the face's line is then no measure of
      // an overlap, and the reaction at the clamped point does not match it: such pairs made
      // energy from nothing (-9.3 MJ/m by 1.9 ms in the SPEC 5.1 bar demo, from 156 pair-steps
      // at up to 6 face lengths outside a quad of the ring around the hole;
      // docs/verification_contact.md). The pair keeps the contact but without force: its depth is
      // ignored (d0, in (c)) while it is off the face, its stored energy booked as dissipated.
      const bool off_face = lowest < -kOffFace;
      cs.pair_g[p] = g;
      cs.pair_n[p] = nrm;
      cs.pair_kf_now[p] = static_cast<std::int8_t>(kf);
      // the pair's claim on the body's contact: a holder (in contact through the same face since
      // the last step) first, else the crossed face's gap a step ago; -inf: not penetrating
      const bool pen = inside && kf >= 0 && g < 0;
      cs.pair_off[p] = off_face;
      cs.pair_margin[p] = !inside ? -1.0 : (pen ? 1.0 : 0.0);
      cs.pair_score[p] = !pen ? -std::numeric_limits<double>::infinity()
                              : (kp >= 0 && kf == kp ? std::numeric_limits<double>::max() : gprev[kf]);
      (void)margin;
      cs.pair_w[p] = w;
    }
  });
  // (b) per node, per body: one block keeps the contact: the one that held it through the same
  // face since the last step, else the one whose face the node crossed (largest gap a step ago),
  // the first of equals
  // (over the near pairs of each node: the others are outside their blocks and hold nothing)
  {
    cs.near_group.clear();  // the start of each node's near pairs in `near` (+ the end)
    for (std::int64_t i = 0; i < nnear; ++i)
      if (i == 0 || cs.near_node[i] != cs.near_node[i - 1]) cs.near_group.push_back(static_cast<std::int32_t>(i));
    cs.near_group.push_back(static_cast<std::int32_t>(nnear));
    const auto nd = static_cast<std::int64_t>(cs.near_group.size()) - 1;
    static LoopSplit split_owner;
    split_owner.run(nd, [&](const LoopSplit::Range& part) {
      for (std::int64_t d = part.lo; d < part.hi; ++d) {
        const auto i0 = cs.near_group[d], i1 = cs.near_group[d + 1];
        for (auto ip = i0; ip < i1; ++ip) {
          const std::int32_t p = cs.near[ip];
          if (cs.pair_margin[p] < 1.0) continue;  // not penetrating
          for (auto iq = i0; iq < i1; ++iq) {
            const std::int32_t q = cs.near[iq];
            if (q == p || cs.pair_margin[q] < 1.0) continue;
            if (cs.body[cs.pair_block[q]] != cs.body[cs.pair_block[p]]) continue;
            const bool q_wins = cs.pair_score[q] > cs.pair_score[p] ||
                                (cs.pair_score[q] == cs.pair_score[p] && q < p);
            if (q_wins) {
              cs.pair_margin[p] = 0.5;  // penetrating, but another block of the body has the contact
              break;
            }
          }
        }
        // The contact of a body moves with the node from block to block: the winner takes over
        // the state (tangential force, gap, ignored depth, last force) of the pair that held it,
        // so the force and the stored energy carry on without a jump.
        for (auto ip = i0; ip < i1; ++ip) {
          const std::int32_t p = cs.near[ip];
          if (cs.pair_margin[p] < 1.0) continue;  // p: the winner of its body
          for (auto iq = i0; iq < i1; ++iq) {
            const std::int32_t q = cs.near[iq];
            if (q == p || cs.body[cs.pair_block[q]] != cs.body[cs.pair_block[p]]) continue;
            if (cs.pair_gap[q] == 0 && cs.pair_fn[q] == 0 && dot(cs.pair_force[q], cs.pair_force[q]) == 0)
              continue;  // q held nothing
            cs.pair_ft[p] = cs.pair_ft[q];
            cs.pair_gap[p] = cs.pair_gap[q];
            // The depth in p's block beyond q's penetration is ignored (d0), so the penetration,
            // the force's magnitude and the stored energy carry on. (With q's d0 instead, a node
            // deeper in p's block than in q's got the difference pushed back at once: energy from
            // nothing, -1.2 MJ by 3 ms in the coarse SPEC 5.3 cylinder, docs/verification.md.)
            cs.pair_g0[p] = std::max(0.0, -cs.pair_g[p] - cs.pair_gap[q]);
            cs.pair_fn[p] = cs.pair_fn[q];
            cs.pair_force[p] = cs.pair_force[q];
            cs.pair_kf[p] = cs.pair_kf_now[p];  // p holds it from now on
            cs.pair_kf[q] = -1;
            cs.pair_ft[q] = {};
            cs.pair_gap[q] = 0;
            cs.pair_g0[q] = 0;
            cs.pair_fn[q] = 0;
            cs.pair_force[q] = {};
          }
        }
      }
    });
  }
  // (c) forces and state of the near pairs
  static LoopSplit split_force;
  const LoopSplit::CountMax touched = split_force.run_reduce(nnear, LoopSplit::CountMax{}, [&](const LoopSplit::Range& part) {
    LoopSplit::CountMax held;
    for (std::int64_t ii = part.lo; ii < part.hi; ++ii) {
      if (ii + kPrefetchAhead < nnear) {
        const auto q = static_cast<std::size_t>(cs.near[ii + kPrefetchAhead]);
        prefetch_at(q, cs.pair_w.data(), cs.pair_g.data(), cs.pair_n.data(), cs.pair_margin.data(),
                    cs.pair_k.data(), cs.pair_kf_now.data());
        prefetch_for_write_at(q, cs.pair_force.data(), cs.pair_gap.data(), cs.pair_ft.data(), cs.pair_g0.data(),
                              cs.pair_kf.data(), cs.pair_diss.data(), cs.pair_fn.data());
      }
      const std::int32_t p = cs.near[ii];
      const std::int32_t n = cs.pair_node[p], b = cs.pair_block[p];
      const std::int32_t n0 = m.block_first_node[b];
      const std::array<double, 4>& w = cs.pair_w[p];
      const double g = cs.pair_g[p];
      const Vec3 nrm = cs.pair_n[p];
      const bool inside = cs.pair_margin[p] >= 0;   // inside the block (whether it won or not)
      const bool kf_ok = cs.pair_margin[p] >= 1.0;  // penetrating, with the contact of the body
      const int nb_nodes = m.block_first_node[b + 1] - n0;
      Vec3 vrel = m.v[n];
      for (int i = 0; i < nb_nodes; ++i) vrel -= w[i] * m.v[n0 + i];
      const Vec3 du = dt * vrel;
      const double k = cs.pair_k[p], kt = cs.shear_ratio * k;
      const Vec3 f_old = cs.pair_force[p];
      const double e_old = 0.5 * k * cs.pair_gap[p] * cs.pair_gap[p] +
                           (kt > 0 ? 0.5 * dot(cs.pair_ft[p], cs.pair_ft[p]) / kt : 0.0);
      const bool in_contact = kf_ok && g < 0;
      const double vn_rel = dot(vrel, nrm);
      // The ignored penetration d0: set when the node comes inside, then only shrinking.
      double d0 = cs.pair_g0[p];
      // coming into contact now (not in contact at the last step): an overlap beyond what one
      // step's approach explains is inherited (the node sank in while it was held by a broken
      // point, or through faces that were not yet candidates), not pushed back at once. Deeper
      // than two steps' approach (and the block's tolerance), the node did not just arrive: none
      // of it is pushed back. (A node 9 cm deep in a 0.2 m tet of the coarse SPEC 5.3 cylinder
      // was taken up as new, pushed back by two steps' approach, dropped as outside the next
      // step, and taken up again, over and over: each push booked as energy made and throwing
      // the node faster, 1.2 MJ and 1.1 km/s by 12.3 ms; docs/pile_pit_3d.md.)
      // Only an approach is pushed back: a node that moves out of the block (vn_rel > 0: along the
      // face's outward normal) did not arrive this step, whatever its depth (it was inside
      // unseen, as where two bodies that overlap part and a node slides out of one block's
      // faces), and pushing |vn| dt back threw it out faster: energy from nothing.
      if (in_contact && cs.pair_kf[p] < 0) {
        const double reach = 2.0 * std::max(0.0, -vn_rel) * dt;
        d0 = -g > reach + cs.cb_geom[cs.pair_cb[p]].tol ? -g : std::max(0.0, -g - reach);
      } else if (in_contact && cs.pair_kf[p] != cs.pair_kf_now[p]) {
        // Held, it changes face (at an edge or a vertex of the block, behind two planes): d0 was
        // the ignored part of the old face's depth and means nothing for the new face's. The
        // new face takes over the old one's pushed depth, no more (its force magnitude carries
        // on, the spring energy does not grow): kept as it was, the new face's whole depth less
        // a d0 worn down on the old face was pushed back at once. A node on a vertex of a block
        // of its own body (the two share that one mesh vertex, no face) switched between two of
        // the vertex's faces every second step, each switch making 3-13 kJ, until the run
        // stopped (coarse SPEC 5.3 scheme B, cracked faces as candidates, 7.02 ms;
        // docs/verification_contact.md).
        d0 = std::max(0.0, -g - cs.pair_gap[p]);
      }
      if (in_contact) d0 = std::min(d0, -g);
      // off its face (above): the whole depth is ignored, the contact kept without force, so that
      // when the node comes back over the face its force grows from zero (dropping the contact and
      // taking it up again as a new one pushed the last two steps' approach back at once, each time:
      // a pump that made 75 MJ from nothing in the coarse SPEC 5.3 cylinder by 13 ms)
      if (in_contact && cs.pair_off[p]) d0 = -g;
      if (!inside) d0 = 0;
      cs.pair_g0[p] = d0;
      Vec3 force{}, ft{};
      double fn = 0, gap = 0;
      if (in_contact && k > 0 && -g > d0) {
        gap = -g - d0;
        const double mu = cs.mu[static_cast<std::size_t>(m.block_region[m.node_block(n)]) * cs.nreg +
                                m.block_region[b]];
        double cdamp = zeta > 0 ? 2.0 * zeta * std::sqrt(k * m.mass[n]) : 0.0;
        // (passivity, above: the node's debt taken back by a dashpot)
        if (const double debt = cs.cfg.passivity ? cs.node_debt[n] : 0.0; debt > 0 && vn_rel != 0)
          cdamp += passivity_dashpot(debt, vn_rel, dt, k, m.mass[n]);
        fn = std::max(0.0, k * gap - cdamp * vn_rel);
        // tangential spring in the current tangent plane (magnitude kept), Coulomb cap
        ft = cs.pair_ft[p];
        const double ft2 = dot(ft, ft);
        ft -= dot(ft, nrm) * nrm;
        const double fp2 = dot(ft, ft);
        if (fp2 > 0) ft *= std::sqrt(ft2 / fp2);
        const Vec3 du_t = du - dot(du, nrm) * nrm;
        ft -= kt * du_t;
        // the tangential dashpot of the same damping ratio (DEM practice: both directions damped)
        const Vec3 ft_total = zeta > 0 ? ft - (2.0 * zeta * std::sqrt(kt * m.mass[n]) / dt) * du_t : ft;
        const double cap = mu * fn;
        double mag = norm(ft);
        if (mag > cap) ft *= (cap > 0 ? cap / mag : 0.0);
        Vec3 fdrag = ft_total;
        mag = norm(fdrag);
        if (mag > cap) fdrag *= (cap > 0 ? cap / mag : 0.0);
        force = fn * nrm + fdrag;
        ++held.count;
        const double ratio = gap / m.block_size[b];  // (the ignored part not counted)
        if (ratio > held.max) held.max = ratio, held.at = p;
      }
      const double e_new = 0.5 * k * gap * gap + (kt > 0 ? 0.5 * dot(ft, ft) / kt : 0.0);
      // work done on the contact by the relative motion: -F . du (F acts on the node)
      const double work = 0.5 * dot(f_old + force, du);
      const double dd_ = -work - (e_new - e_old);
      cs.pair_diss[p] += dd_;
      // (to the node's debt: what is more than the round-off of the energies it is made of; a
      // resting contact's last bits would otherwise keep a dashpot on)
      cs.near_dd[ii] = std::abs(dd_) > 1e-12 * (e_old + e_new + std::abs(work)) ? dd_ : 0.0;
      cs.pair_fn[p] = fn;
      cs.pair_ft[p] = ft;
      cs.pair_gap[p] = gap;
      cs.pair_force[p] = force;
      cs.pair_kf[p] = in_contact ? cs.pair_kf_now[p] : static_cast<std::int8_t>(-1);
      cs.near_forced[ii] = force.x != 0 || force.y != 0 || force.z != 0;
    }
    return held;
  }, LoopSplit::CountMax::join);
  active += touched.count;
  pen_ratio = std::max(pen_ratio, touched.max);
  // (c') edge-to-edge contacts (3D), their forces added to f first, in their list's order
  if (cs.edges) edge_contact_forces(m, cs, dt, active, pen_ratio);
  if (pen_ratio > cs.max_pen_ratio) {  // the run's largest penetration grows: where
    if (touched.at >= 0 && touched.max == pen_ratio) {
      const auto p = static_cast<std::size_t>(touched.at);
      cs.max_pen_at = {-1, cs.pair_node[p], cs.pair_block[p], -1, m.x[cs.pair_node[p]], true};
    } else {
      locate_edge_penetration(m, cs, pen_ratio);  // (contact_edges.cpp)
    }
  }
  cs.active = active;
  cs.active_max = std::max(cs.active_max, active);
  cs.max_pen_ratio = std::max(cs.max_pen_ratio, pen_ratio);
  // Gathers in a fixed order, each node's sum formed first and then added: node side, then face
  // side, each in pair order, so the sums are the same for any thread count. The node side in
  // parallel (a node's near pairs are one run of the list), the face side serially (the forces
  // of the few pairs in contact, scattered over the blocks' nodes).
  // The node's passivity debt is booked in the same pass, in pair order.
  const auto ng = static_cast<std::int64_t>(cs.near_group.size()) - 1;
  const bool passive = cs.cfg.passivity;
  static LoopSplit split_gather;
  split_gather.run(ng, [&](const LoopSplit::Range& part) {
    for (std::int64_t d = part.lo; d < part.hi; ++d) {
      Vec3 acc{};
      bool any = false;
      const std::int32_t n = cs.near_node[cs.near_group[d]];
      double debt = cs.node_debt[n];
      for (auto i = cs.near_group[d]; i < cs.near_group[d + 1]; ++i) {
        if (cs.near_forced[i]) acc += cs.pair_force[cs.near[i]], any = true;
        debt -= cs.near_dd[i];
      }
      if (any) m.f[n] += acc;
      if (passive) cs.node_debt[n] = std::max(0.0, debt);
    }
  });
  cs.face_touched.clear();
  cs.face_sum.clear();
  for (std::int64_t i = 0; i < nnear; ++i) {
    if (!cs.near_forced[i]) continue;
    const std::int32_t p = cs.near[i];
    const Vec3 F = cs.pair_force[p];
    const std::int32_t b = cs.pair_block[p], n0 = m.block_first_node[b];
    const int nbn = m.block_first_node[b + 1] - n0;
    for (int k = 0; k < nbn; ++k) {
      std::int32_t& slot = cs.face_slot[n0 + k];
      if (slot < 0) {
        slot = static_cast<std::int32_t>(cs.face_touched.size());
        cs.face_touched.push_back(n0 + k);
        cs.face_sum.push_back(Vec3{});
      }
      cs.face_sum[slot] += cs.pair_w[p][k] * F;
    }
  }
  for (std::size_t j = 0; j < cs.face_touched.size(); ++j) {
    m.f[cs.face_touched[j]] -= cs.face_sum[j];
    cs.face_slot[cs.face_touched[j]] = -1;
  }
}

}  // namespace cdem
