// The release trigger's neighbourhood (physics/contact.hpp, contact.cpp): which groups of blocks
// lay near a block whose spring points were released since the last build, and how fast they
// move.
//
// Why. Released points make their faces candidates, but their pairs are found only at the next
// rebuild. Until then no node can come nearer a released face than the relative motion since the
// release allows, so the rebuild waits until that bound reaches kReleaseDrift x skin (a contact
// found late overlaps at most that much). The bound was 2 max|v| dt per step with max|v| the
// fastest node of the whole model: in the fine SPEC 5.3 cylinder at 3 ms the fastest nodes fly
// at 400-440 m/s near the holes while the blocks released are moving at 30-80 m/s, and 10 of the
// 19 rebuilds in 300 steps were release rebuilds on that bound.
//
// The bound split in two. At the step a block is released (the spring kernel's positions, which
// contact_forces sees unchanged), every group of blocks whose box lies within L = kReleaseFar x
// skin of the block's box (on some axis farther: then farther in space) is marked near until the
// next build.
// - A node of a near group and a released face of a near block (the block's own group is near)
//   approach each other by at most 2 v_near dt per step, v_near the largest speed of the near
//   groups' nodes (a group marked later is near for the releases from then on, and far for the
//   earlier ones).
// - A node of any other group was farther than L from the block at its release, so it can reach
//   its face only once 2 max|v| dt has summed past L.
// So the rebuild is due when the near sum passes kReleaseDrift x skin or the far sum passes
// (kReleaseDrift + kReleaseFar) x skin: the same overlap bound as before. With every group near
// the rule is the old one, bit for bit (v_near is then max|v|): a checkpoint written before the
// split continues that way until its next build.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "cdem/core/loop_split.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {
namespace {

// Released spring points on the interfaces of block b (at most 6 faces x a few points: a byte).
std::uint8_t released_on_block(const Model& m, std::int32_t b) {
  const int np = m.springs_per_iface;
  int count = 0;
  for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1]; ++e) {
    const std::size_t i = static_cast<std::size_t>(block_iface_index(m.block_iface_list[e]));
    for (int q = 0; q < np; ++q) count += m.sp_state[i * np + q] == kReleased;
  }
  return static_cast<std::uint8_t>(std::min(count, 255));
}

// Is every spring point of interface i released (the interface no longer joins its blocks into
// one body: contact_broad_phase.cpp)?
bool fully_released(const Model& m, std::size_t i) {
  const int np = m.springs_per_iface;
  for (int q = 0; q < np; ++q)
    if (m.sp_state[i * np + q] != kReleased) return false;
  return true;
}

// Is block a still joined to block b (through interfaces with a point not released) by a path
// found breadth first within kJoinSearch blocks of a? 1: yes. 0: no, and a's whole body is the
// first `size` entries of queue (fewer than kJoinSearch blocks: the search ran out). -1: not
// shown (a path longer than the search, or a large body). queue and hash: scratch of
// kJoinSearch and 2 kJoinSearch entries (the hash a set of the blocks queued, open addressing).
constexpr int kJoinSearch = 4096;
int still_joined(const Model& m, std::int32_t a, std::int32_t b, std::int32_t* queue, std::int32_t* hash, int& size) {
  constexpr std::uint32_t mask = 2 * kJoinSearch - 1;
  std::fill(hash, hash + 2 * kJoinSearch, -1);
  auto insert = [&](std::int32_t k) {  // false: already there
    std::uint32_t h = (static_cast<std::uint32_t>(k) * 2654435761u) & mask;
    while (hash[h] >= 0) {
      if (hash[h] == k) return false;
      h = (h + 1) & mask;
    }
    hash[h] = k;
    return true;
  };
  int head = 0, tail = 0;
  queue[tail++] = a;
  insert(a);
  while (head < tail) {
    const std::int32_t k = queue[head++];
    for (auto e = m.block_iface_offset[k]; e < m.block_iface_offset[k + 1]; ++e) {
      const std::int32_t code = m.block_iface_list[e];
      const std::size_t i = static_cast<std::size_t>(block_iface_index(code));
      if (fully_released(m, i)) continue;
      const std::int32_t other = code > 0 ? m.iface_block_b[i] : m.iface_block_a[i];
      if (other == b) return 1;
      if (tail == kJoinSearch) return -1;
      if (insert(other)) queue[tail++] = other;
    }
  }
  size = tail;
  return 0;
}

// More groups with new releases in one step than this: every group is marked near (the old
// rule until the next build) instead of testing each against every group box.
constexpr std::size_t kMaxReleaseGroups = 64;

}  // namespace

void sync_release_counts(const Model& m, ContactSet& cs) {
  const auto nb = static_cast<std::int64_t>(m.n_blocks());
  const auto ni = static_cast<std::int64_t>(m.n_ifaces());
  cs.blk_released.resize(static_cast<std::size_t>(nb));
  cs.ifc_free.resize(static_cast<std::size_t>(ni));
#pragma omp parallel for schedule(static)
  for (std::int64_t b = 0; b < nb; ++b) cs.blk_released[b] = released_on_block(m, static_cast<std::int32_t>(b));
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < ni; ++i) cs.ifc_free[i] = fully_released(m, static_cast<std::size_t>(i));
  cs.released_looked = m.released_points;
  // (the per-group boxes and the split test's scratch: a step allocates nothing)
  const std::size_t ng = cs.grp_speed.size();
  for (auto* v : {&cs.grp_lo, &cs.grp_hi, &cs.rel_lo, &cs.rel_hi}) v->resize(ng);
  cs.rel_groups.reserve(std::max<std::size_t>(ng, kMaxReleaseGroups));
  cs.join_queue.reserve(kJoinSearch);
  cs.join_hash.reserve(2 * kJoinSearch);
}

void reset_release_trigger(const Model& m, ContactSet& cs) {
  const auto nb = static_cast<std::int64_t>(m.n_blocks());
  sync_release_counts(m, cs);
  cs.blk_near.assign(static_cast<std::size_t>(nb), 0);
  cs.release_drift_far = 0;
}

double release_near_speed(const Model& m, ContactSet& cs, double reach) {
  const auto ng = static_cast<std::int64_t>(cs.grp_speed.size());
  const auto nb = static_cast<std::int64_t>(m.n_blocks());
  const std::uint8_t* const skip = m.no_contact.empty() ? nullptr : m.no_contact.data();
  if (cs.blk_near.size() != static_cast<std::size_t>(nb) || cs.blk_released.size() != static_cast<std::size_t>(nb) ||
      cs.ifc_free.size() != m.n_ifaces() || cs.grp_lo.size() != static_cast<std::size_t>(ng)) {
    // (a checkpoint written before the split: every block near, the far sum the old one, so the
    // old rule until the next build)
    const double drift = cs.release_drift;
    reset_release_trigger(m, cs);
    std::fill(cs.blk_near.begin(), cs.blk_near.end(), std::uint8_t{1});
    cs.release_drift_far = drift;
  } else if (cs.released_looked != m.released_points) {
    // 1. Per group, the box of its blocks released since the last look (a block's count of
    // released points grew), each group by one thread: the same boxes for any thread count.
    constexpr double inf = std::numeric_limits<double>::infinity();
    static LoopSplit split_look;
    split_look.run(ng, [&](const LoopSplit::Range& part) {
      for (std::int64_t g = part.lo; g < part.hi; ++g) {
        Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
        for (std::int64_t b = g * kSleepGroup; b < std::min(nb, (g + 1) * kSleepGroup); ++b) {
          const std::uint8_t now = released_on_block(m, static_cast<std::int32_t>(b));
          if (now == cs.blk_released[b]) continue;
          cs.blk_released[b] = now;
          Vec3 a, c;
          m.block_box(static_cast<std::size_t>(b), a, c);
          for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], a[d]), hi[d] = std::max(hi[d], c[d]);
        }
        cs.rel_lo[g] = lo;
        cs.rel_hi[g] = hi;
      }
    });
    cs.rel_groups.clear();  // (within its capacity)
    for (std::int64_t g = 0; g < ng; ++g)
      if (cs.rel_lo[g].x <= cs.rel_hi[g].x) cs.rel_groups.push_back(static_cast<std::int32_t>(g));
    // An interface whose last point was released may split a body in two. The nodes of either
    // part then pair with the blocks of the other anywhere the two touch, not only near the
    // released block (pairs within a body are not listed, contact_broad_phase.cpp), so the bound
    // of the near blocks does not hold for them: unless its two blocks are shown still joined,
    // every block is near until the next build (the old rule).
    // Where the split is shown (one part's whole body found, under kJoinSearch blocks), every new
    // pair has a node or a block in that part, and the other side within a skin of it: its
    // blocks count as released (their boxes join their groups' release boxes).
    bool split = cs.rel_groups.size() > kMaxReleaseGroups;
    const std::size_t nrel = cs.rel_groups.size();  // (the groups with releases; parts add more)
    cs.join_queue.resize(kJoinSearch);  // (within their capacity: reset_release_trigger)
    cs.join_hash.resize(2 * kJoinSearch);
    for (std::size_t r = 0; r < nrel && !split; ++r) {
      const std::int64_t g = cs.rel_groups[r];
      for (std::int64_t b = g * kSleepGroup; b < std::min(nb, (g + 1) * kSleepGroup) && !split; ++b)
        for (auto e = m.block_iface_offset[b]; e < m.block_iface_offset[b + 1] && !split; ++e) {
          const std::size_t i = static_cast<std::size_t>(block_iface_index(m.block_iface_list[e]));
          if (cs.ifc_free[i] || !fully_released(m, i)) continue;
          cs.ifc_free[i] = 1;
          const std::int32_t ba = m.iface_block_a[i], bb = m.iface_block_b[i];
          int size = 0;
          int joined = still_joined(m, ba, bb, cs.join_queue.data(), cs.join_hash.data(), size);
          if (joined < 0) joined = still_joined(m, bb, ba, cs.join_queue.data(), cs.join_hash.data(), size);
          if (joined > 0) continue;
          if (joined < 0) {
            split = true;
            break;
          }
          for (int j = 0; j < size; ++j) {  // (the part found: its blocks' boxes)
            const std::int32_t k = cs.join_queue[static_cast<std::size_t>(j)];
            const std::int64_t gk = k / kSleepGroup;
            if (!(cs.rel_lo[gk].x <= cs.rel_hi[gk].x)) {
              if (cs.rel_groups.size() >= kMaxReleaseGroups) {
                split = true;
                break;
              }
              cs.rel_groups.push_back(static_cast<std::int32_t>(gk));
            }
            Vec3 lo, hi;
            m.block_box(static_cast<std::size_t>(k), lo, hi);
            for (int d = 0; d < 3; ++d)
              cs.rel_lo[gk][d] = std::min(cs.rel_lo[gk][d], lo[d]), cs.rel_hi[gk][d] = std::max(cs.rel_hi[gk][d], hi[d]);
          }
        }
    }
    if (split) sync_release_counts(m, cs);  // (the interfaces not looked at)
    // 2. The blocks within reach of those boxes (on every axis; beyond it on one axis is beyond
    // it in space) are near: first their groups' boxes (this step's, from the speed pass), then
    // each block's. Each group and its blocks are marked by one thread.
    if (split) {
      std::fill(cs.blk_near.begin(), cs.blk_near.end(), std::uint8_t{1});
    } else if (!cs.rel_groups.empty()) {
      const int dim = m.dim;
      auto within = [&](const Vec3& lo, const Vec3& hi, std::int32_t h) {
        bool near = true;
        for (int d = 0; d < dim; ++d) near = near && cs.rel_lo[h][d] - reach <= hi[d] && lo[d] <= cs.rel_hi[h][d] + reach;
        return near;
      };
#pragma omp parallel for schedule(static)
      for (std::int64_t g = 0; g < ng; ++g) {
        bool any = false;
        for (const std::int32_t h : cs.rel_groups) any = any || within(cs.grp_lo[g], cs.grp_hi[g], h);
        if (!any) continue;
        for (std::int64_t b = g * kSleepGroup; b < std::min(nb, (g + 1) * kSleepGroup); ++b) {
          if (cs.blk_near[b] || (skip && skip[b])) continue;
          Vec3 lo, hi;
          m.block_box(static_cast<std::size_t>(b), lo, hi);
          for (const std::int32_t h : cs.rel_groups)
            if (within(lo, hi, h)) {
              cs.blk_near[b] = 1;
              break;
            }
        }
      }
    }
    cs.released_looked = m.released_points;
  }
  // 3. The largest speed of the near blocks' nodes, now (a maximum: the same in any order).
  static LoopSplit split_speed;
  return std::sqrt(split_speed.run_reduce(nb, 0.0, [&](const LoopSplit::Range& part) {
    double v = 0;
    for (std::int64_t b = part.lo; b < part.hi; ++b) {
      if (!cs.blk_near[b] || (skip && skip[b])) continue;
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) v = std::max(v, dot(m.v[n], m.v[n]));
    }
    return v;
  }, [](double x, double y) { return std::max(x, y); }));
}

}  // namespace cdem
