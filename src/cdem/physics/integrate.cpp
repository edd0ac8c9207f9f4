#include "cdem/physics/integrate.hpp"

#include <cmath>

namespace cdem {
namespace {

// One version of the loop per damping case, so that the common undamped model pays neither
// the damping arrays' loads nor the divisions by 1 + c dt/2 nor the dissipation book-keeping.
// Every version does the same arithmetic as the general formula: c = 0 gives (1 - 0) v = v,
// a division by 1 (exact) and a dissipation increment of +0, so skipping them changes no bit.
template <bool kViscous, bool kLocal>
void integrate_blocks(Model& m, Vec3 gravity, double dt, double* dissipated, double* ke,
                      double* cke) {
  const auto nb = static_cast<std::int64_t>(m.n_blocks());
  const std::int32_t* first = m.block_first_node.data();
  const double* damping = kViscous ? m.damping.data() : nullptr;
  const double* local = kLocal ? m.local_damping.data() : nullptr;
#pragma omp parallel for schedule(static)
  for (std::int64_t b = 0; b < nb; ++b) {
    double ke_b = 0, cke_b = 0, diss_b = 0;
    for (std::int32_t n = first[b]; n < first[b + 1]; ++n) {
      const double mass = m.mass[n];
      const Vec3 v0 = m.v[n];
      Vec3 f = m.f[n] + mass * gravity;
      Vec3 fd{};
      if constexpr (kLocal) {
        const double al = local[n];
        if (al > 0) {
          // Local damping (Cundall): opposes the velocity with a fraction of the unbalanced force.
          for (int k = 0; k < 3; ++k) fd[k] = -al * std::abs(f[k]) * (v0[k] > 0 ? 1.0 : (v0[k] < 0 ? -1.0 : 0.0));
          f += fd;
        }
      }
      Vec3 v1;
      double c = 0;
      if constexpr (kViscous) {
        c = damping[n];
        const double cdt = 0.5 * c * dt;
        v1 = ((1.0 - cdt) * v0 + (dt / mass) * f) / (1.0 + cdt);
      } else {
        v1 = v0 + (dt / mass) * f;
      }
      m.v[n] = v1;
      const Vec3 vmid = 0.5 * (v0 + v1);
      // Viscous: c m |v_mid|^2 dt; local: -F_d . v_mid dt.
      if constexpr (kViscous || kLocal) diss_b += dt * (c * mass * dot(vmid, vmid) - dot(fd, vmid));
      if (ke) {
        const double ke_n = 0.5 * mass * dot(vmid, vmid);
        ke_b += ke_n;
        if constexpr (kViscous) cke_b += c * ke_n;
      }
    }
    if constexpr (kViscous || kLocal) dissipated[b] += diss_b;
    if (ke) {
      ke[b] = ke_b;
      if (cke) cke[b] = cke_b;
    }
  }
}

}  // namespace

void integrate(Model& m, Vec3 gravity, double dt, double* dissipated, double* ke, double* cke) {
  const bool viscous = !m.damping.empty(), local = !m.local_damping.empty();
  if (viscous && local)
    integrate_blocks<true, true>(m, gravity, dt, dissipated, ke, cke);
  else if (viscous)
    integrate_blocks<true, false>(m, gravity, dt, dissipated, ke, cke);
  else if (local)
    integrate_blocks<false, true>(m, gravity, dt, dissipated, ke, cke);
  else
    integrate_blocks<false, false>(m, gravity, dt, dissipated, ke, cke);
}

void release_zero_damping(Model& m) {
  auto all_zero = [](const std::vector<double>& a) {
    for (double c : a)
      if (c != 0) return false;
    return true;
  };
  if (all_zero(m.damping)) std::vector<double>().swap(m.damping);
  if (all_zero(m.local_damping)) std::vector<double>().swap(m.local_damping);
}

void update_positions(Model& m, double dt) {
  const auto nn = static_cast<std::int64_t>(m.n_nodes());
#pragma omp parallel for schedule(static)
  for (std::int64_t n = 0; n < nn; ++n) m.x[n] += dt * m.v[n];
}

}  // namespace cdem
