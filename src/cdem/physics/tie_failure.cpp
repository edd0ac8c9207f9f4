#include "cdem/physics/tie_failure.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "cdem/core/loop_split.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/ties.hpp"

namespace cdem {
namespace {

struct FaceTraction {
  Vec3 n;       // unit normal, A to B
  double tn;    // t . n (Pa), tension positive
  Vec3 ts;      // tangential traction (Pa)
};

// ½ (sigma_A + sigma_B) a: the mean of the two blocks' stresses (Sym6: xx, yy, zz, xy, yz, xz)
// applied to the vector a (a unit normal, or an area vector for a traction times area).
inline Vec3 mean_traction(const Model& m, std::int64_t i, const Vec3& a) {
  const Sym6& sa = m.stress[m.iface_block_a[i]];
  const Sym6& sb = m.stress[m.iface_block_b[i]];
  const double xx = 0.5 * (sa[0] + sb[0]), yy = 0.5 * (sa[1] + sb[1]), zz = 0.5 * (sa[2] + sb[2]);
  const double xy = 0.5 * (sa[3] + sb[3]), yz = 0.5 * (sa[4] + sb[4]), xz = 0.5 * (sa[5] + sb[5]);
  return {xx * a.x + xy * a.y + xz * a.z, xy * a.x + yy * a.y + yz * a.z,
          xz * a.x + yz * a.y + zz * a.z};
}

FaceTraction face_traction(const Model& m, std::int64_t i) {
  const int np = m.springs_per_iface;
  const std::int64_t s0 = i * np;
  Vec3 pa[3], pb[3];
  for (int q = 0; q < np; ++q) {
    pa[q] = m.x[m.sp_a[s0 + q]];
    pb[q] = m.x[m.sp_b[s0 + q]];
  }
  const Vec3 av = face_area_vector(std::span<const Vec3>(pa, np), np) +
                  face_area_vector(std::span<const Vec3>(pb, np), np);
  const double a2 = dot(av, av);
  const Vec3 n = a2 > 0 ? (1.0 / std::sqrt(a2)) * av : Vec3{};
  const Vec3 t = mean_traction(m, i, n);
  const double tn = dot(t, n);
  return {n, tn, t - tn * n};
}

inline void cap(Vec3& fs, double c) {
  const double mag = norm(fs);
  if (mag > c) fs *= (c > 0 ? c / mag : 0.0);
}

}  // namespace

std::uint8_t tie_strength_exceeded(const SpringLaw& law, double fn, double fs2, double area) {
  switch (law.law) {
    case InterfaceLaw::Elastic: return kModeNone;
    case InterfaceLaw::MohrCoulomb:
    case InterfaceLaw::FractureEnergy: {
      if (fn >= law.ft * area) return kModeTension;
      const double tau = law.c * area - fn * law.tan_phi;
      if (tau <= 0 || fs2 >= tau * tau) return kModeShear;
      return kModeNone;
    }
  }
  return kModeNone;
}

double tie_failure(Model& m, double t, std::vector<std::uint8_t>& flag,
                   std::vector<std::pair<std::int64_t, double>>* terms) {
  if (terms) terms->clear();
  const auto ni = static_cast<std::int64_t>(m.n_ifaces());
  const int np = m.springs_per_iface;
  if (flag.size() != static_cast<std::size_t>(ni)) flag.assign(ni, 0);
  static LoopSplit split;
  const std::int64_t failed = split.run_reduce(ni, std::int64_t{0}, [&](const LoopSplit::Range& part) {
    std::int64_t n_failed = 0;
    for (std::int64_t i = part.lo; i < part.hi; ++i) {
      if (!m.iface_check[i]) continue;
      // Quick reject from the stresses alone: |t| = |sigma n| <= ||sigma||_F for any unit n, and a
      // tie can only break if t_n >= f_t or |t_s| >= c - t_n tan(phi) >= c - |t| tan(phi), so
      // never while ||sigma||_F < min(f_t, c / (1 + tan(phi))) (tie_reject_stress). Most ties,
      // away from the wave fronts, stop here without gathering their face.
      {
        const Sym6& sa = m.stress[m.iface_block_a[i]];
        const Sym6& sb = m.stress[m.iface_block_b[i]];
        double f2 = 0;
        for (int k = 0; k < 6; ++k) {
          const double v = 0.5 * (sa[k] + sb[k]);
          f2 += (k < 3 ? 1.0 : 2.0) * v * v;
        }
        const double thr = m.tie_reject[m.iface_material[i]];
        if (f2 < thr * thr) {
          flag[i] = kModeNone;
          continue;
        }
      }
      // The traction on the face of A (a tied face's nodes coincide with B's) from its area vector
      // a, without a square root: t_n = (sigma a . a) / (a . a), |t_s|^2 = |sigma a|^2 / (a . a) - t_n^2.
      const std::int64_t s0 = i * np;
      const Vec3 p0 = m.x[m.sp_a[s0]], p1 = m.x[m.sp_a[s0 + 1]];
      Vec3 a;
      if (np == 3) {
        a = cross(p1 - p0, m.x[m.sp_a[s0 + 2]] - p0);
      } else {
        const Vec3 e = p1 - p0;
        a = {e.y, -e.x, 0.0};
      }
      const Vec3 ta = mean_traction(m, i, a);
      const double aa = dot(a, a);
      if (!(aa > 0)) continue;
      const double inv = 1.0 / aa;
      const double tn = dot(ta, a) * inv;
      const double ts2 = std::max(0.0, dot(ta, ta) * inv - tn * tn);
      const double area = m.sp_area.v[i];
      const SpringLaw& law = m.spring_laws[m.iface_material[i]];
      const std::uint8_t mode = tie_strength_exceeded(law, tn * area, ts2 * area * area, area);
      flag[i] = mode;
      n_failed += mode != kModeNone;
    }
    return n_failed;
  }, std::plus<>{});
  if (failed == 0) return 0.0;
  // The failed interfaces (flag: the mode in bits 0-1), in three passes.
  // (1) In parallel over the interfaces: each failed one's traction, and its tied points' new
  // state and force (per point: no two interfaces write the same); the points to untie are
  // marked in flag bits 2-4 (one per point, np <= 3). The interface's normal is this traction's.
  split.run(ni, [&](const LoopSplit::Range& part) {
    for (std::int64_t i = part.lo; i < part.hi; ++i) {
      if (flag[i] == kModeNone) continue;
      const std::uint8_t mode = flag[i];
      const FaceTraction tr = face_traction(m, i);
      const double area = m.sp_area.v[i], kn = m.sp_kn.v[i];
      const SpringLaw& law = m.spring_laws[m.iface_material[i]];
      std::uint8_t marks = mode;
      for (int q = 0; q < np; ++q) {
        const std::size_t s = static_cast<std::size_t>(i) * np + q;
        if (!m.sp_tied[s]) continue;
        double fn = tr.tn * area;
        Vec3 fs = area * tr.ts;
        if (law.law == InterfaceLaw::MohrCoulomb) {
          m.sp_state[s] = kBroken;
          m.sp_mode[s] = mode;
          m.sp_break_time[s] = static_cast<float>(t);
          fn = std::min(0.0, fn);
          cap(fs, -fn * law.tan_phi_r);
        } else {  // fracture energy: a cohesive point at its peak strength, zero opening
          fn = std::min(fn, law.ft * area);
          cap(fs, std::max(0.0, law.c * area - fn * law.tan_phi));
        }
        m.sp_fn[s] = fn;
        m.sp_fs[s] = fs;
        m.sp_g0[s] = kn > 0 ? fn / kn : 0.0;
        marks |= static_cast<std::uint8_t>(4 << q);
      }
      flag[i] = marks;
      if (marks >= 4) m.iface_normal[i] = tr.n;
    }
  });
  // (2) The clusters, in parallel over the mesh vertices: each thread unties the marked points of
  // its range of vertices (a point's two nodes are split from one vertex, and a split touches
  // that vertex's nodes and tied points only), in interface order; the clusters do not depend
  // on the order (untie_at_vertex).
  const auto nv = static_cast<std::int64_t>(m.n_vertices());
  const int nt = std::min(omp_get_max_threads(), kMaxUntieThreads);
#pragma omp parallel num_threads(nt)
  {
    const int th = omp_get_thread_num(), nth = omp_get_num_threads();
    const std::int64_t v_lo = nv * th / nth, v_hi = nv * (th + 1) / nth;
    for (std::int64_t i = 0; i < ni; ++i) {
      if (flag[i] < 4) continue;
      for (int q = 0; q < np; ++q) {
        if (!(flag[i] & (4 << q))) continue;
        const std::size_t s = static_cast<std::size_t>(i) * np + q;
        const std::int64_t v = m.node_vertex[m.sp_a[s]];
        if (v >= v_lo && v < v_hi) untie_at_vertex(m, s, th);
      }
    }
  }
  // (3) Serially, in interface order: the active list, the check flags, the forces on the nodes
  // and the insertion energy (sums in a fixed order).
  double insertion = 0;
  for (std::int64_t i = 0; i < ni; ++i) {
    if (flag[i] == kModeNone) continue;
    const std::uint8_t marks = flag[i];
    flag[i] = kModeNone;
    if (marks < 4) continue;  // (no tied point left: nothing changes)
    const Vec3 n = m.iface_normal[i];
    after_untie(m, static_cast<std::int32_t>(i));
    m.iface_normal[i] = n;  // (the traction's normal, not the one activation computes)
    const double kn = m.sp_kn.v[i], ks = m.sp_ks.v[i];
    for (int q = 0; q < np; ++q) {
      if (!(marks & (4 << q))) continue;
      const std::size_t s = static_cast<std::size_t>(i) * np + q;
      const double fn = m.sp_fn[s];
      const Vec3 fs = m.sp_fs[s];
      const double e = 0.5 * fn * fn / kn + 0.5 * dot(fs, fs) / ks;
      insertion += e;
      if (terms) terms->emplace_back(static_cast<std::int64_t>(s), e);
      const Vec3 f = fn * n + fs;
      m.f[m.sp_a[s]] += f;
      m.f[m.sp_b[s]] -= f;
    }
  }
  return insertion;
}

}  // namespace cdem
