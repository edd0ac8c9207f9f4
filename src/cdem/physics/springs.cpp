#include "cdem/physics/springs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "cdem/core/loop_split.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {
namespace {

// a / |a| with one division (normalized() divides each component), 0 for a = 0.
inline Vec3 unit(Vec3 a) {
  const double n2 = dot(a, a);
  return n2 > 0 ? (1.0 / std::sqrt(n2)) * a : Vec3{};
}

inline double elastic_energy(const SpringPoint& sp) {
  return 0.5 * sp.fn * sp.fn / sp.kn + 0.5 * dot(sp.fs, sp.fs) / sp.ks;
}

inline void cap_shear(Vec3& fs, double cap) {
  const double m = norm(fs);
  if (m > cap) fs *= (cap > 0 ? cap / m : 0.0);
}

// The release distance of interface i's broken points this step, from its two faces' area
// vectors aa and ab (their dot product and squared lengths): release_distance_factor x the mean
// size of its two blocks; or -1 (every broken point released, whatever its d) once the faces
// have turned apart by more than the release angle (Model::release_cos). A broken point is a
// contact along the interface's mean normal unit(aa + ab); as the faces turn towards opposite
// sides that sum cancels and its direction is rounding: coarse SPEC 5.3 scheme B had two
// tumbling tets with faces 177 degrees apart whose last broken point, pushed along such a
// normal, made 5.8 MJ in 15 steps (docs/verification_contact.md). General contact takes over.
// (The distance is computed unconditionally: a conditional load of block_size left one of the
// chunk's gather loops scalar.)
inline double broken_release(const Model& m, std::int64_t i, double ab, double aa2, double ab2) {
  const double rd = m.release_distance_factor * 0.5 *
                    (m.block_size[m.iface_block_a[i]] + m.block_size[m.iface_block_b[i]]);
  return ab < m.release_cos * std::sqrt(aa2 * ab2) ? -1.0 : rd;
}

void break_spring(SpringPoint& sp, std::uint8_t mode, double t) {
  sp.state = kBroken;
  sp.mode = mode;
  sp.break_time = static_cast<float>(t);
}

// Broken: compression only (faces in contact when d_n < 0) and Coulomb friction.
inline void broken_law(SpringPoint& sp, const SpringLaw& law, double dn) {
  sp.fn = std::min(0.0, sp.kn * dn);
  cap_shear(sp.fs, -sp.fn * law.tan_phi_r);
}

void mohr_coulomb(SpringPoint& sp, const SpringLaw& law, double dn, double t) {
  sp.fn = sp.kn * dn;
  if (sp.fn >= law.ft * sp.area) {
    break_spring(sp, kModeTension, t);
  } else if (norm(sp.fs) >= law.c * sp.area - sp.fn * law.tan_phi) {
    break_spring(sp, kModeShear, t);
  }
  if (sp.state == kBroken) broken_law(sp, law, dn);
}

void fracture_energy(SpringPoint& sp, const SpringLaw& law, double dn, double t) {
  const double ftA = law.ft * sp.area, cA = law.c * sp.area;
  auto dt_of = [&](double w) { return law.wc > 0 ? w / law.wc : (w > 0 ? 1.0 : 0.0); };
  auto ds_of = [&](double s) { return law.sc > 0 ? s / law.sc : (s > 0 ? 1.0 : 0.0); };
  const double open = dn - sp.dil;
  // ---- tension: f_t(w) = f_t0 (1 - D) with D = max(w / w_c, s / s_c) ----
  double dmg_s = ds_of(sp.slip);
  double fn = sp.kn * (open - sp.w);
  const double ft_now = ftA * (1.0 - std::max(dt_of(sp.w), dmg_s));
  if (fn > ft_now) {
    double w_new;
    const double soft = sp.kn - (law.wc > 0 ? ftA / law.wc : 0.0);  // > 0 unless snap-back
    const double w_soft = soft > 0 ? (sp.kn * open - ftA) / soft : law.wc;
    if (dt_of(w_soft) >= dmg_s)
      w_new = w_soft;  // on the softening line
    else
      w_new = open - ftA * (1.0 - dmg_s) / sp.kn;  // strength already lowered by shear
    sp.w = std::max(sp.w, std::min(w_new, std::max(law.wc, 0.0)));
    fn = sp.kn * (open - sp.w);
    if (dt_of(sp.w) >= 1.0) fn = std::min(fn, 0.0);
  }
  sp.fn = fn;
  // ---- shear: c(s) = c0 (1 - D), strength c A - F_n tan(phi) ----
  double dmg = std::max(dt_of(sp.w), ds_of(sp.slip));
  double tau = std::max(0.0, cA * (1.0 - dmg) - sp.fn * law.tan_phi);
  const double fs_mag = norm(sp.fs);
  if (fs_mag > tau && dmg < 1.0) {
    const double excess = fs_mag - tau;
    const bool shear_governs = ds_of(sp.slip) >= dt_of(sp.w);
    const double soft = sp.ks - (shear_governs && law.sc > 0 ? cA / law.sc : 0.0);
    double ds = soft > 0 ? excess / soft : law.sc;
    ds = std::min(ds, std::max(law.sc - sp.slip, 0.0) + excess / sp.ks);
    sp.slip += ds;
    sp.dil += ds * law.tan_psi;
    dmg = std::max(dt_of(sp.w), ds_of(sp.slip));
    tau = std::max(0.0, cA * (1.0 - std::min(dmg, 1.0)) - sp.fn * law.tan_phi);
    cap_shear(sp.fs, tau);
  }
  if (dmg >= 1.0) {
    break_spring(sp, dt_of(sp.w) >= ds_of(sp.slip) ? kModeTension : kModeShear, t);
    broken_law(sp, law, dn);
  }
}

}  // namespace

Vec3 update_spring_point(SpringPoint& sp, const SpringLaw& law, Vec3 d, Vec3 du, Vec3 n, double t,
                         double release_distance, Vec3 force_old) {
  if (sp.state == kReleased) return {};
  const double e_old = elastic_energy(sp);
  // Keep the shear force in the current tangent plane, preserving its magnitude:
  // |F_s| / |F_s,proj| as one square root of the ratio of the squares (as spring_forces).
  const double fs_old2 = dot(sp.fs, sp.fs);
  sp.fs -= dot(sp.fs, n) * n;
  const double fs_proj2 = dot(sp.fs, sp.fs);
  if (fs_proj2 > 0) sp.fs *= std::sqrt(fs_old2 / fs_proj2);
  const double du_n = dot(du, n);
  sp.fs += sp.ks * (du - du_n * n);
  const double dn = dot(d, n) + sp.g0;
  if (sp.state == kBroken) {
    if (norm(d) > release_distance) {
      sp.state = kReleased;
      sp.fn = 0;
      sp.fs = {};
    } else {
      broken_law(sp, law, dn);
    }
  } else {
    switch (law.law) {
      case InterfaceLaw::Elastic: sp.fn = sp.kn * dn; break;
      case InterfaceLaw::MohrCoulomb: mohr_coulomb(sp, law, dn, t); break;
      case InterfaceLaw::FractureEnergy: fracture_energy(sp, law, dn, t); break;
    }
    // broken now between faces turned apart (release_distance < 0, broken_release): released at
    // once, not pushed along their mean normal for a step
    if (sp.state == kBroken && release_distance < 0) {
      sp.state = kReleased;
      sp.fn = 0;
      sp.fs = {};
    }
  }
  const Vec3 force = sp.fn * n + sp.fs;
  sp.dissipated += 0.5 * dot(force_old + force, du) - (elastic_energy(sp) - e_old);
  return force;
}

namespace {

// The full update of spring point s (interface i) with the dissipation book-keeping: breaking,
// broken contact and friction, softening (fracture-energy law), release (a broken point beyond
// `release`, broken_release).
// Returns 1 when the point was released in this update (else 0).
int spring_full_update(Model& m, const SpringLaw& law, std::int64_t i, std::int64_t s, Vec3 d,
                       Vec3 du, Vec3 n, Vec3 n_old, double off, double t, bool fe, double release) {
  const double kn = m.sp_kn.v[i], ks = m.sp_ks.v[i], area = m.sp_area.v[i];
  const double fn_old = m.sp_fn[s];
  const std::uint8_t state_old = m.sp_state[s];
  const Vec3 fs_old = m.sp_fs[s];
  SpringPoint sp{kn,     ks,           area,    fn_old,
                 fs_old, fe ? m.sp_w[s] : 0.0, fe ? m.sp_slip[s] : 0.0, fe ? m.sp_dil[s] : 0.0,
                 m.sp_state[s], m.sp_mode[s], m.sp_break_time[s], m.sp_dissipated[s], off};
  // The force of the previous step, F_n n_old + F_s (spring_force with the normal then).
  update_spring_point(sp, law, d, du, n, t, release, fn_old * n_old + fs_old);
  m.sp_fn[s] = sp.fn;
  m.sp_fs[s] = sp.fs;
  if (fe) {
    m.sp_w[s] = sp.w;
    m.sp_slip[s] = sp.slip;
    m.sp_dil[s] = sp.dil;
  }
  m.sp_state[s] = sp.state;
  m.sp_mode[s] = sp.mode;
  m.sp_break_time[s] = sp.break_time;
  m.sp_dissipated[s] = sp.dissipated;
  return state_old != kReleased && sp.state == kReleased;
}

// One interface of the reference form. kTied: tied points (Model::sp_tied) are skipped (no
// force, no update) and the previous normal is always the kept one.
template <bool kTied>
inline int spring_interface(Model& m, std::int64_t i, double dt, double t, bool have_old,
                            bool fe) {
  const int np = m.springs_per_iface;
  int released = 0;
  {
    const std::int64_t s0 = i * np;
    Vec3 pa[3], pb[3];
    for (int q = 0; q < np; ++q) {
      pa[q] = m.x[m.sp_a[s0 + q]];
      pb[q] = m.x[m.sp_b[s0 + q]];
    }
    const Vec3 aa = face_area_vector(std::span<const Vec3>(pa, np), np),
               ab = face_area_vector(std::span<const Vec3>(pb, np), np);
    const Vec3 n = unit(aa + ab);
    const double release = broken_release(m, i, dot(aa, ab), dot(aa, aa), dot(ab, ab));
    // The previous normal: kept from the previous call (x then was x - v dt up to rounding);
    // on the first call rebuilt from the previous positions x - v dt.
    Vec3 n_old;
    if (have_old) {
      n_old = m.iface_normal[i];
    } else {
      Vec3 qa[3], qb[3];
      for (int q = 0; q < np; ++q) {
        qa[q] = pa[q] - dt * m.v[m.sp_a[s0 + q]];
        qb[q] = pb[q] - dt * m.v[m.sp_b[s0 + q]];
      }
      n_old = unit(face_area_vector(std::span<const Vec3>(qa, np), np) +
                   face_area_vector(std::span<const Vec3>(qb, np), np));
    }
    m.iface_normal[i] = n;
    // The interface's spin over the step. A change of more than 0.1 rad in one step is not a
    // rotation but a degenerate or flipping face (an inverted block): no correction then.
    Vec3 dn_vec = n - n_old;
    if (dot(dn_vec, dn_vec) > 0.01) dn_vec = {};
    const double* g0 = m.sp_g0.empty() ? nullptr : m.sp_g0.data();
    const SpringLaw& law = m.spring_laws[m.iface_material[i]];
    const double kn = m.sp_kn.v[i], ks = m.sp_ks.v[i], area = m.sp_area.v[i];
    for (int q = 0; q < np; ++q) {
      const std::int64_t s = s0 + q;
      const std::uint8_t state = m.sp_state[s];
      if (state == kReleased) continue;  // F_n = 0, F_s = 0 since it was released
      if constexpr (kTied) {
        if (m.sp_tied[s]) continue;  // a tie: no spring force
      }
      const auto a = m.sp_a[s], b = m.sp_b[s];
      const Vec3 d = pb[q] - pa[q];
      // Objective increment: remove the part of the relative motion that only carries the
      // normal gap d_n around with the spinning interface.
      const Vec3 du = dt * (m.v[b] - m.v[a]) - dot(d, n) * dn_vec;
      const double off = g0 ? g0[s] : 0.0;
      // Fast path: an intact spring point on an elastic branch (the elastic law, Mohr-Coulomb
      // before it breaks, the fracture-energy law while it neither softens nor breaks: its
      // F_n = k_n (open - w) with its damage state unchanged) stores energy without dissipating
      // it, so only its forces are updated. Any other state (breaking now, softening now,
      // broken) takes the full update with the dissipation book-keeping. (Before 4 Dec 2026
      // the fracture-energy law always took the full update: the same forces and state, bit for
      // bit, and a dissipation that differed by the rounding of the elastic steps' work.)
      // (the tied mode's fracture-energy points always take the full update: they are untied at
      // their peak strength, so nearly all soften; spring_chunk)
      if (state == kIntact && !(kTied && law.law == InterfaceLaw::FractureEnergy)) {
        Vec3 fs = m.sp_fs[s];
        const double fs_old2 = dot(fs, fs);
        fs -= dot(fs, n) * n;
        const double fs_proj2 = dot(fs, fs);
        // Rescale to the old magnitude: |F_s| / |F_s,proj| as one square root of the ratio.
        if (fs_proj2 > 0) fs *= std::sqrt(fs_old2 / fs_proj2);
        fs += ks * (du - dot(du, n) * n);
        bool holds;
        double fn;
        if (law.law == InterfaceLaw::FractureEnergy) {
          fn = kn * (((dot(d, n) + off) - m.sp_dil[s]) - m.sp_w[s]);
          holds = fe_elastic(law, area, m.sp_w[s], m.sp_slip[s], fn, dot(fs, fs));
        } else {
          fn = kn * (dot(d, n) + off);
          // |F_s| < tau, tested on the squares (tau > 0 first).
          const double tau = law.c * area - fn * law.tan_phi;
          holds = law.law == InterfaceLaw::Elastic ||
                  (fn < law.ft * area && tau > 0 && dot(fs, fs) < tau * tau);
        }
        if (holds) {
          m.sp_fn[s] = fn;
          m.sp_fs[s] = fs;
          continue;
        }
      }
      released += spring_full_update(m, law, i, s, d, du, n, n_old, off, t, fe, release);
    }
  }
  return released;
}

// The reference form, one interface at a time: the first call (no previous normal kept) and
// any spring_points_per_iface other than 2 or 3.
void spring_forces_generic(Model& m, double dt, double t, std::int64_t lo, std::int64_t hi) {
  const auto ni = std::min(hi, static_cast<std::int64_t>(m.n_ifaces()));
  const bool have_old = m.iface_normal_set;
  const bool fe = !m.sp_w.empty();  // fracture-energy state kept (release_unused_spring_state)
  std::int64_t released = 0;
#pragma omp parallel for schedule(static) reduction(+ : released)
  for (std::int64_t i = lo; i < ni; ++i) released += spring_interface<false>(m, i, dt, t, have_old, fe);
  m.released_points += released;
  m.iface_normal_set = true;
}

// Tied mode: the active interfaces only (those with an untied point; their normals are kept
// from activation on), tied points skipped.
void spring_forces_tied(Model& m, double dt, double t, std::int64_t lo, std::int64_t hi) {
  const auto na = std::min(hi, static_cast<std::int64_t>(m.active_ifaces.size()));
  const bool fe = !m.sp_w.empty();
  const std::int32_t* list = m.active_ifaces.data();
  std::int64_t released = 0;
#pragma omp parallel for schedule(static) reduction(+ : released)
  for (std::int64_t k = lo; k < na; ++k) released += spring_interface<true>(m, list[k], dt, t, true, fe);
  m.released_points += released;
  m.iface_normal_set = true;
}

// Interfaces per chunk of the vectorised kernel. GCC 12 picks the vector width from the largest
// trip count the loop can have: 32 interfaces (96 spring points) let it use 64-byte vectors for
// the spring loop (8 interfaces gave 16-byte ones). The stack arrays take ~20 KB (L1d: 48 KiB).
constexpr int kChunk = 32;

// The same arithmetic as spring_forces_generic (every expression in the same order, so the
// results are bitwise the same), organised for SIMD over a chunk of kChunk interfaces:
//  1. per interface (one SIMD lane each): gather the face nodes, the new normal, the spin
//     n - n_old, the spring constants and the law's parameters into stack arrays;
//  2. per spring point of the chunk (contiguous s): the fast path of an intact spring point on
//     an elastic branch (a linear law, or the fracture-energy law neither softening nor
//     breaking), as masked stores; a flag for the others (breaking or softening now, broken);
//  3. the flagged ones, one at a time, through the full update.
// The law of each interface is read per lane.
// kList (tied mode): the chunk is entries i0 .. i0 + w - 1 of `list` (the active interfaces), not
// interfaces i0 .. i0 + w - 1, and tied points are skipped (no force, no update: as
// spring_interface<true>); the spring points' state is copied into contiguous arrays of the
// chunk for the spring loop (GCC 12 does not vectorise it with indexed loads and stores) and
// copied back after it.
template <int NP, bool kG0, bool kList = false>
int spring_chunk(Model& m, std::int64_t i0, int w, double dt, double t, bool fe,
                 const std::int32_t* list = nullptr) {
  // Per interface (index l) the previous normal; per spring point of the chunk (index k = l NP + q,
  // the interface's values repeated NP times, so that the spring loop reads them contiguously)
  // the normal, the spin, the constants and the law's parameters.
  constexpr int K = kChunk * NP;
  alignas(64) double ox[kChunk], oy[kChunk], oz[kChunk];
  alignas(64) double nx[K], ny[K], nz[K], ex[K], ey[K], ez[K];
  alignas(64) double kn_l[K], ks_l[K], area_l[K], ft_l[K], c_l[K], tphi_l[K];
  alignas(64) int kind_l[K];  // 0 elastic, 1 Mohr-Coulomb, 2 fracture energy
  alignas(64) int slow[K], keep[K];
  alignas(64) double fsx0[K], fsy0[K], fsz0[K];
  alignas(64) double dx[K], dy[K], dz[K], dvx[K], dvy[K], dvz[K];  // x_b - x_a, v_b - v_a
  alignas(64) double onx[K], ony[K], onz[K], rel_l[K], tphir_l[K];  // for broken spring points
  alignas(64) double wc_l[K], sc_l[K];  // the fracture-energy law's w_c and s_c
  alignas(64) std::int64_t sidx[kList ? K : 1];  // kList: the spring point of each k
  alignas(64) int skip[kList ? K : 1];           // kList: a tied point
  // Component loads and stores (an aggregate Vec3 copy is not vectorised by GCC 12).
  const double* x = reinterpret_cast<const double*>(m.x.data());
  const double* v = reinterpret_cast<const double*>(m.v.data());
  const std::int32_t* sa = m.sp_a.data();
  const std::int32_t* sb = m.sp_b.data();
  const SpringLaw* laws = m.spring_laws.data();
  const std::int32_t* mat = m.iface_material.data();
  double* normal = reinterpret_cast<double*>(m.iface_normal.data());
#pragma omp simd
  for (int l = 0; l < w; ++l) {
    const std::int64_t i = kList ? list[i0 + l] : i0 + l, s0 = i * NP;
    if constexpr (kList)
      for (int q = 0; q < NP; ++q) {
        sidx[l * NP + q] = s0 + q;
        skip[l * NP + q] = m.sp_tied[s0 + q] != 0;
      }
    // The face nodes' positions and velocities (the only gathers of the kernel): d = x_b - x_a
    // and dv = v_b - v_a per spring point, kept for the spring loop.
    double pax[NP], pay[NP], paz[NP], pbx[NP], pby[NP], pbz[NP];
    for (int q = 0; q < NP; ++q) {
      const std::int64_t a = 3 * sa[s0 + q], b = 3 * sb[s0 + q];
      pax[q] = x[a]; pay[q] = x[a + 1]; paz[q] = x[a + 2];
      pbx[q] = x[b]; pby[q] = x[b + 1]; pbz[q] = x[b + 2];
      const int k = l * NP + q;
      dx[k] = pbx[q] - pax[q];
      dy[k] = pby[q] - pay[q];
      dz[k] = pbz[q] - paz[q];
      dvx[k] = v[b] - v[a];
      dvy[k] = v[b + 1] - v[a + 1];
      dvz[k] = v[b + 2] - v[a + 2];
    }
    // each face's area vector (face_area_vector) and their sum
    double aax, aay, aaz, abx, aby, abz, sx, sy, sz;
    if constexpr (NP == 3) {
      // 0.5 cross(p1 - p0, p2 - p0) of each face
      const double ax1 = pax[1] - pax[0], ay1 = pay[1] - pay[0], az1 = paz[1] - paz[0];
      const double ax2 = pax[2] - pax[0], ay2 = pay[2] - pay[0], az2 = paz[2] - paz[0];
      const double bx1 = pbx[1] - pbx[0], by1 = pby[1] - pby[0], bz1 = pbz[1] - pbz[0];
      const double bx2 = pbx[2] - pbx[0], by2 = pby[2] - pby[0], bz2 = pbz[2] - pbz[0];
      aax = 0.5 * (ay1 * az2 - az1 * ay2);
      aay = 0.5 * (az1 * ax2 - ax1 * az2);
      aaz = 0.5 * (ax1 * ay2 - ay1 * ax2);
      abx = 0.5 * (by1 * bz2 - bz1 * by2);
      aby = 0.5 * (bz1 * bx2 - bx1 * bz2);
      abz = 0.5 * (bx1 * by2 - by1 * bx2);
    } else {
      const double tax = pax[1] - pax[0], tay = pay[1] - pay[0];
      const double tbx = pbx[1] - pbx[0], tby = pby[1] - pby[0];
      aax = tay; aay = -tax; aaz = 0.0;
      abx = tby; aby = -tbx; abz = 0.0;
    }
    sx = aax + abx;
    sy = aay + aby;
    sz = aaz + abz;
    // unit(sum): (1 / |sum|) sum, 0 for sum = 0
    const double n2 = sx * sx + sy * sy + sz * sz;
    const double r = 1.0 / std::sqrt(n2);
    const double nxl = n2 > 0 ? r * sx : 0.0, nyl = n2 > 0 ? r * sy : 0.0,
                 nzl = n2 > 0 ? r * sz : 0.0;
    const double oxl = normal[3 * i], oyl = normal[3 * i + 1], ozl = normal[3 * i + 2];
    normal[3 * i] = nxl;
    normal[3 * i + 1] = nyl;
    normal[3 * i + 2] = nzl;
    const double e0x = nxl - oxl, e0y = nyl - oyl, e0z = nzl - ozl;
    const bool flip = e0x * e0x + e0y * e0y + e0z * e0z > 0.01;  // no spin correction
    ox[l] = oxl; oy[l] = oyl; oz[l] = ozl;
    const double exl = flip ? 0.0 : e0x, eyl = flip ? 0.0 : e0y, ezl = flip ? 0.0 : e0z;
    const double knl = m.sp_kn.v[i], ksl = m.sp_ks.v[i], al = m.sp_area.v[i];
    const SpringLaw& law = laws[mat[i]];
    const double ftl = law.ft, cl = law.c, tpl = law.tan_phi, tprl = law.tan_phi_r;
    const double wcl = law.wc, scl = law.sc;
    const double rel = broken_release(m, i, aax * abx + aay * aby + aaz * abz,
                                      aax * aax + aay * aay + aaz * aaz,
                                      abx * abx + aby * aby + abz * abz);
    const int kl = static_cast<int>(law.law);
    for (int q = 0; q < NP; ++q) {
      const int k = l * NP + q;
      nx[k] = nxl; ny[k] = nyl; nz[k] = nzl;
      ex[k] = exl; ey[k] = eyl; ez[k] = ezl;
      kn_l[k] = knl; ks_l[k] = ksl; area_l[k] = al;
      ft_l[k] = ftl; c_l[k] = cl; tphi_l[k] = tpl;
      kind_l[k] = kl;
      onx[k] = oxl; ony[k] = oyl; onz[k] = ozl;
      rel_l[k] = rel; tphir_l[k] = tprl;
      wc_l[k] = wcl; sc_l[k] = scl;
    }
  }
  const double* g0 = kG0 ? m.sp_g0.data() : nullptr;
  double* fn_out = m.sp_fn.data();
  double* diss_io = m.sp_dissipated.data();
  double* fs_io = reinterpret_cast<double*>(m.sp_fs.data());
  const std::uint8_t* state_in = m.sp_state.data();
  // the fracture-energy state (read only here: a point that softens takes the full update)
  const double* w_in = fe ? m.sp_w.data() : nullptr;
  const double* slip_in = fe ? m.sp_slip.data() : nullptr;
  const double* dil_in = fe ? m.sp_dil.data() : nullptr;
  std::int64_t s_begin = i0 * NP;
  // Does the chunk hold an intact fracture-energy point? Only then does the spring loop test
  // the law's elastic branch: most chunks of a cracked model hold broken points only, and the
  // test's loads, divisions and square root cost them more than it saves. Springs mode only:
  // in the tied mode a fracture-energy point is untied at its peak strength and softens from
  // there (tie_failure.hpp), so its intact points are nearly all softening, and the test cost
  // the late SPEC 5.3 state's spring kernel 5-15 % (docs/performance.md): they take the full
  // update, as spring_interface<true> does.
  bool fe_intact = false;
  if (fe && !kList)
    for (int k = 0; k < w * NP; ++k)
      fe_intact |= (kind_l[k] == static_cast<int>(InterfaceLaw::FractureEnergy)) &
                   (state_in[s_begin + k] == kIntact);
  constexpr int KL = kList ? K : 1;  // the chunk's copies (kList)
  alignas(64) double g0_c[KL], fn_c[KL], diss_c[KL], fs_c[3 * KL];
  alignas(64) std::uint8_t state_c[KL];
  if constexpr (kList) {
    for (int k = 0; k < w * NP; ++k) {
      const std::int64_t s = sidx[k];
      if constexpr (kG0) g0_c[k] = m.sp_g0[s];
      fn_c[k] = fn_out[s];
      diss_c[k] = diss_io[s];
      fs_c[3 * k] = fs_io[3 * s];
      fs_c[3 * k + 1] = fs_io[3 * s + 1];
      fs_c[3 * k + 2] = fs_io[3 * s + 2];
      state_c[k] = state_in[s];
    }
    g0 = g0_c;
    fn_out = fn_c;
    diss_io = diss_c;
    fs_io = fs_c;
    state_in = state_c;
    s_begin = 0;
  }
  // The spring loop, with or without the broken-contact path: its square roots and divisions
  // cost about as much as the rest, so chunks without a broken spring point (most: cracks are
  // local) skip it; and with or without the fracture-energy law's elastic branch (kFE: the
  // chunk has an intact point under that law, fe_intact above).
  auto spring_loop = [&](auto with_broken, auto with_fe) {
  constexpr bool kBroken = decltype(with_broken)::value;
  constexpr bool kFE = decltype(with_fe)::value;
#pragma omp simd
  for (int k = 0; k < w * NP; ++k) {
    const std::int64_t s = s_begin + k;
    const int state = state_in[s];
    const bool tied = kList ? skip[k] != 0 : false;
    const double n_x = nx[k], n_y = ny[k], n_z = nz[k];
    const double dn = dx[k] * n_x + dy[k] * n_y + dz[k] * n_z;
    // du = dt (v_b - v_a) - (d . n) e
    const double dux = dt * dvx[k] - dn * ex[k];
    const double duy = dt * dvy[k] - dn * ey[k];
    const double duz = dt * dvz[k] - dn * ez[k];
    double off = 0.0;
    if constexpr (kG0) off = g0[s];
    const double fx0 = fs_io[3 * s], fy0 = fs_io[3 * s + 1], fz0 = fs_io[3 * s + 2];
    double fx = fx0, fy = fy0, fz = fz0;
    const double fs_old2 = fx * fx + fy * fy + fz * fz;
    const double fsn = fx * n_x + fy * n_y + fz * n_z;
    fx -= fsn * n_x;
    fy -= fsn * n_y;
    fz -= fsn * n_z;
    const double fs_proj2 = fx * fx + fy * fy + fz * fz;
    const double scale = std::sqrt(fs_old2 / fs_proj2);
    if (fs_proj2 > 0) {
      fx *= scale;
      fy *= scale;
      fz *= scale;
    }
    const double dun = dux * n_x + duy * n_y + duz * n_z;
    const double ks = ks_l[k];
    fx += ks * (dux - dun * n_x);
    fy += ks * (duy - dun * n_y);
    fz += ks * (duz - dun * n_z);
    const double fn_lin = kn_l[k] * (dn + off);
    const double tau = c_l[k] * area_l[k] - fn_lin * tphi_l[k];
    const int kind = kind_l[k];
    const double fs2 = fx * fx + fy * fy + fz * fz;
    // Non-short-circuit & and |: a && would put the loads behind branches (no vectorisation).
    bool holds = (kind == static_cast<int>(InterfaceLaw::Elastic)) |
                 ((fn_lin < ft_l[k] * area_l[k]) & (tau > 0) & (fs2 < tau * tau));
    double fn = fn_lin;
    bool fe_ok = kind != static_cast<int>(InterfaceLaw::FractureEnergy);
    if constexpr (kFE) {
      // the fracture-energy law's elastic branch (springs.hpp)
      const double wv = w_in[s];
      const double fn_fe = kn_l[k] * (((dn + off) - dil_in[s]) - wv);
      const bool holds_fe = fe_elastic(wc_l[k], sc_l[k], ft_l[k] * area_l[k], c_l[k] * area_l[k],
                                       tphi_l[k], wv, slip_in[s], fn_fe, fs2);
      const bool is_fe = !fe_ok;
      holds = is_fe ? holds_fe : holds;
      fn = is_fe ? fn_fe : fn_lin;
      fe_ok = true;
    }
    const bool fast = (state == kIntact) & fe_ok & holds & !tied;
    bool broken = false;
    double fnb = 0, bsc = 1, diss = 0;
    if constexpr (kBroken) {
      // A broken spring point that stays within the release distance: contact and Coulomb
      // friction (broken_law) with the dissipation book-keeping of update_spring_point, the same
      // expressions in the same order.
      const double kn = kn_l[k];
      fnb = std::min(0.0, kn * (dn + off));
      const double cap = -fnb * tphir_l[k];
      const double mag = std::sqrt(fx * fx + fy * fy + fz * fz);
      const double capf = cap > 0 ? cap / mag : 0.0;
      // F_s scaled down to the cap (x 1.0 is exact where it is not over it): the factor, not the
      // value, is selected, so that GCC keeps the stores below unconditional.
      bsc = mag > cap ? capf : 1.0;
      const double bx = fx * bsc, by = fy * bsc, bz = fz * bsc;
      broken = (state == kBroken) &
               !(std::sqrt(dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k]) > rel_l[k]) & !tied;
      const double fn_old = fn_out[s];
      const double e_old = 0.5 * fn_old * fn_old / kn + 0.5 * fs_old2 / ks;
      const double fox = fn_old * onx[k] + fx0, foy = fn_old * ony[k] + fy0,
                   foz = fn_old * onz[k] + fz0;
      const double Fx = fnb * n_x + bx, Fy = fnb * n_y + by, Fz = fnb * n_z + bz;
      const double e_new = 0.5 * fnb * fnb / kn + 0.5 * (bx * bx + by * by + bz * bz) / ks;
      diss =
          diss_io[s] +
          (0.5 * ((fox + Fx) * dux + (foy + Fy) * duy + (foz + Fz) * duz) - (e_new - e_old));
    }
    // F_s is stored unconditionally (GCC 12 has no masked stores for the interleaved x, y, z;
    // a select of the old value is turned back into one): the old value is kept on the stack
    // and put back below where neither path applies.
    if (fast | broken) fn_out[s] = fast ? fn : fnb;
    if constexpr (kBroken) {
      if (broken) diss_io[s] = diss;
    }
    const double store_sc = broken ? bsc : 1.0;
    fs_io[3 * s] = fx * store_sc;
    fs_io[3 * s + 1] = fy * store_sc;
    fs_io[3 * s + 2] = fz * store_sc;
    fsx0[k] = fx0;
    fsy0[k] = fy0;
    fsz0[k] = fz0;
    const bool done = fast | broken;
    keep[k] = !done;
    slow[k] = (!done) & (state != kReleased) & !tied;
  }
  };
  bool any_broken = false;
  for (int k = 0; k < w * NP; ++k) any_broken |= state_in[s_begin + k] == kBroken;
  auto run = [&](auto with_fe) {
    if (any_broken)
      spring_loop(std::true_type{}, with_fe);
    else
      spring_loop(std::false_type{}, with_fe);
  };
  if (fe_intact && !kList)  // (kList: the fracture-energy branch is not instantiated)
    run(std::bool_constant<!kList>{});
  else
    run(std::false_type{});
  if constexpr (kList)  // the chunk's copies back (unchanged values where nothing was written)
    for (int k = 0; k < w * NP; ++k) {
      const std::int64_t s = sidx[k];
      m.sp_fn[s] = fn_c[k];
      m.sp_dissipated[s] = diss_c[k];
      m.sp_fs[s] = Vec3{fs_c[3 * k], fs_c[3 * k + 1], fs_c[3 * k + 2]};
    }
  // (Counted here: a simd reduction in the loop above made GCC 12 leave that loop scalar.)
  int n_keep = 0;  // spring points neither vector path takes
  for (int k = 0; k < w * NP; ++k) n_keep += keep[k];
  if (n_keep == 0) return 0;
  for (int k = 0; k < w * NP; ++k)
    if (keep[k]) m.sp_fs[kList ? sidx[k] : s_begin + k] = Vec3{fsx0[k], fsy0[k], fsz0[k]};
  int released = 0;
  for (int k = 0; k < w * NP; ++k) {
    if (!slow[k]) continue;
    const int l = k / NP;
    const std::int64_t s = kList ? sidx[k] : s_begin + k;
    const Vec3 n{nx[k], ny[k], nz[k]}, e{ex[k], ey[k], ez[k]}, n_old{ox[l], oy[l], oz[l]};
    const Vec3 d{dx[k], dy[k], dz[k]};
    const Vec3 du = dt * Vec3{dvx[k], dvy[k], dvz[k]} - dot(d, n) * e;
    const double off = kG0 ? m.sp_g0[s] : 0.0;
    const std::int64_t i = kList ? list[i0 + l] : i0 + l;
    released += spring_full_update(m, laws[mat[i]], i, s, d, du, n, n_old, off, t, fe, rel_l[k]);
  }
  return released;
}

// Every interface in chunks (springs mode), or (kList, the tied mode) the active interfaces --
// those with an untied point, their normals kept from activation on -- in chunks of that list,
// tied points skipped: the same arithmetic as spring_forces_generic and spring_forces_tied.
template <int NP, bool kG0, bool kList = false>
void spring_forces_chunked(Model& m, double dt, double t, std::int64_t lo, std::int64_t hi) {
  const std::int32_t* list = kList ? m.active_ifaces.data() : nullptr;
  const auto ni = std::min(hi, static_cast<std::int64_t>(kList ? m.active_ifaces.size() : m.n_ifaces()));
  const std::int64_t nc = ni > lo ? (ni - lo + kChunk - 1) / kChunk : 0;
  const bool fe = !m.sp_w.empty();
  static LoopSplit split;  // (the chunks of opened, softening points cost several elastic ones)
  const std::int64_t released = split.run_reduce(nc, std::int64_t{0}, [&](const LoopSplit::Range& r) {
    std::int64_t n_released = 0;
    for (std::int64_t c = r.lo; c < r.hi; ++c) {
      const std::int64_t i0 = lo + c * kChunk;
      n_released += spring_chunk<NP, kG0, kList>(
          m, i0, static_cast<int>(std::min<std::int64_t>(kChunk, ni - i0)), dt, t, fe, list);
    }
    return n_released;
  }, std::plus<>{});
  m.released_points += released;
  if (kList) m.iface_normal_set = true;
}

}  // namespace

void spring_forces(Model& m, double dt, double t, std::int64_t lo, std::int64_t hi) {
  if (m.iface_normal.size() != m.n_ifaces()) {
    m.iface_normal.assign(m.n_ifaces(), Vec3{});
    m.iface_normal_set = false;
  }
  const bool g0 = !m.sp_g0.empty();
  if (m.tied) {
    if (m.springs_per_iface == 3)
      g0 ? spring_forces_chunked<3, true, true>(m, dt, t, lo, hi) : spring_forces_chunked<3, false, true>(m, dt, t, lo, hi);
    else if (m.springs_per_iface == 2)
      g0 ? spring_forces_chunked<2, true, true>(m, dt, t, lo, hi) : spring_forces_chunked<2, false, true>(m, dt, t, lo, hi);
    else
      spring_forces_tied(m, dt, t, lo, hi);
    return;
  }
  if (!m.iface_normal_set || (m.springs_per_iface != 2 && m.springs_per_iface != 3)) {
    spring_forces_generic(m, dt, t, lo, hi);
  } else if (m.springs_per_iface == 3) {
    g0 ? spring_forces_chunked<3, true>(m, dt, t, lo, hi) : spring_forces_chunked<3, false>(m, dt, t, lo, hi);
  } else {
    g0 ? spring_forces_chunked<2, true>(m, dt, t, lo, hi) : spring_forces_chunked<2, false>(m, dt, t, lo, hi);
  }
}

int spring_state_doubles(const Model& m) {
  return 3 + m.springs_per_iface * (m.sp_w.empty() ? 8 : 11);
}

namespace {
// One interface's state to `buf` (kPack) or from it: the same order both ways.
template <bool kPack, class M>
void move_spring_state(M& m, std::int64_t i, std::conditional_t<kPack, double, const double>* buf) {
  auto io = [&](auto& v) {
    if constexpr (kPack)
      *buf++ = static_cast<double>(v);
    else
      v = static_cast<std::remove_reference_t<decltype(v)>>(*buf++);
  };
  io(m.iface_normal[i].x);
  io(m.iface_normal[i].y);
  io(m.iface_normal[i].z);
  const bool fe = !m.sp_w.empty();
  const int np = m.springs_per_iface;
  for (std::int64_t s = i * np; s < (i + 1) * np; ++s) {
    io(m.sp_fn[s]);
    io(m.sp_fs[s].x);
    io(m.sp_fs[s].y);
    io(m.sp_fs[s].z);
    io(m.sp_state[s]);
    io(m.sp_mode[s]);
    io(m.sp_break_time[s]);
    io(m.sp_dissipated[s]);
    if (fe) {
      io(m.sp_w[s]);
      io(m.sp_slip[s]);
      io(m.sp_dil[s]);
    }
  }
}
}  // namespace

void pack_spring_state(const Model& m, const std::int32_t* list, std::int64_t lo, std::int64_t hi,
                       double* out) {
  const int d = spring_state_doubles(m);
#pragma omp parallel for schedule(static)
  for (std::int64_t k = lo; k < hi; ++k)
    move_spring_state<true>(m, list ? list[k] : k, out + (k - lo) * d);
}

void unpack_spring_state(Model& m, const std::int32_t* list, std::int64_t lo, std::int64_t hi,
                         const double* in) {
  const int d = spring_state_doubles(m);
#pragma omp parallel for schedule(static)
  for (std::int64_t k = lo; k < hi; ++k)
    move_spring_state<false>(m, list ? list[k] : k, in + (k - lo) * d);
}

void spring_forces_reference(Model& m, double dt, double t) {
  if (m.iface_normal.size() != m.n_ifaces()) {
    m.iface_normal.assign(m.n_ifaces(), Vec3{});
    m.iface_normal_set = false;
  }
  constexpr auto all = std::numeric_limits<std::int64_t>::max();
  if (m.tied)
    spring_forces_tied(m, dt, t, 0, all);
  else
    spring_forces_generic(m, dt, t, 0, all);
}

void gather_spring_forces(Model& m) {
  const auto nb = static_cast<std::int32_t>(m.n_blocks());
  static LoopSplit split;  // (the blocks with active interfaces gather, the others do not)
  split.run(nb, [&](const LoopSplit::Range& r) {
    for (auto b = static_cast<std::int32_t>(r.lo); b < r.hi; ++b) add_spring_forces(m, b);
  });
}

void release_unused_spring_state(Model& m) {
  for (const auto& law : m.spring_laws)
    if (law.law == InterfaceLaw::FractureEnergy) return;
  auto zero = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return x == 0.0; });
  };
  if (!zero(m.sp_w) || !zero(m.sp_slip) || !zero(m.sp_dil)) return;
  for (auto* v : {&m.sp_w, &m.sp_slip, &m.sp_dil}) std::vector<double>().swap(*v);
}

}  // namespace cdem
