#include "cdem/physics/springs.hpp"

#include <algorithm>
#include <cmath>

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
  // Keep the shear force in the current tangent plane, preserving its magnitude.
  const double fs_old = norm(sp.fs);
  sp.fs -= dot(sp.fs, n) * n;
  const double fs_proj = norm(sp.fs);
  if (fs_proj > 0) sp.fs *= fs_old / fs_proj;
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
  }
  const Vec3 force = sp.fn * n + sp.fs;
  sp.dissipated += 0.5 * dot(force_old + force, du) - (elastic_energy(sp) - e_old);
  return force;
}

void spring_forces(Model& m, double dt, double t) {
  const int np = m.springs_per_iface;
  const auto ni = static_cast<std::int64_t>(m.n_ifaces());
  if (m.iface_normal.size() != m.n_ifaces()) {
    m.iface_normal.assign(m.n_ifaces(), Vec3{});
    m.iface_normal_set = false;
  }
  const bool have_old = m.iface_normal_set;
  const bool fe = !m.sp_w.empty();  // fracture-energy state kept (release_unused_spring_state)
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < ni; ++i) {
    const std::int64_t s0 = i * np;
    Vec3 pa[3], pb[3];
    for (int q = 0; q < np; ++q) {
      pa[q] = m.x[m.sp_a[s0 + q]];
      pb[q] = m.x[m.sp_b[s0 + q]];
    }
    const Vec3 n = unit(face_area_vector(std::span<const Vec3>(pa, np), np) +
                        face_area_vector(std::span<const Vec3>(pb, np), np));
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
      const auto a = m.sp_a[s], b = m.sp_b[s];
      const Vec3 d = pb[q] - pa[q];
      // Objective increment: remove the part of the relative motion that only carries the
      // normal gap d_n around with the spinning interface.
      const Vec3 du = dt * (m.v[b] - m.v[a]) - dot(d, n) * dn_vec;
      const double off = g0 ? g0[s] : 0.0;
      // Fast path: an intact spring point under a linear law (elastic, or Mohr-Coulomb before
      // it breaks) stores energy without dissipating it, so only its forces are updated. Any
      // other state (breaking now, broken, softening) takes the full update with the
      // dissipation book-keeping.
      if (state == kIntact && law.law != InterfaceLaw::FractureEnergy) {
        Vec3 fs = m.sp_fs[s];
        const double fs_old2 = dot(fs, fs);
        fs -= dot(fs, n) * n;
        const double fs_proj2 = dot(fs, fs);
        // Rescale to the old magnitude: |F_s| / |F_s,proj| as one square root of the ratio.
        if (fs_proj2 > 0) fs *= std::sqrt(fs_old2 / fs_proj2);
        fs += ks * (du - dot(du, n) * n);
        const double fn = kn * (dot(d, n) + off);
        // |F_s| < tau, tested on the squares (tau > 0 first).
        const double tau = law.c * area - fn * law.tan_phi;
        const bool holds = law.law == InterfaceLaw::Elastic ||
                           (fn < law.ft * area && tau > 0 && dot(fs, fs) < tau * tau);
        if (holds) {
          m.sp_fn[s] = fn;
          m.sp_fs[s] = fs;
          continue;
        }
      }
      const double fn_old = m.sp_fn[s];
      const Vec3 fs_old = m.sp_fs[s];
      SpringPoint sp{kn,     ks,           area,    fn_old,
                     fs_old, fe ? m.sp_w[s] : 0.0, fe ? m.sp_slip[s] : 0.0, fe ? m.sp_dil[s] : 0.0,
                     state,  m.sp_mode[s], m.sp_break_time[s], m.sp_dissipated[s], off};
      const double release = m.release_distance_factor * 0.5 *
                             (m.block_size[m.iface_block_a[i]] + m.block_size[m.iface_block_b[i]]);
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
    }
  }
  m.iface_normal_set = true;
}

void gather_spring_forces(Model& m) {
  const auto nb = static_cast<std::int32_t>(m.n_blocks());
#pragma omp parallel for schedule(static)
  for (std::int32_t b = 0; b < nb; ++b) add_spring_forces(m, b);
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
