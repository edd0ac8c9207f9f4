#include "cdem/physics/integrate.hpp"

#include <cmath>

namespace cdem {

void integrate(Model& m, Vec3 gravity, double dt, std::vector<double>& dissipated, double* ke) {
  const auto nn = static_cast<std::int64_t>(m.n_nodes());
#pragma omp parallel for schedule(static)
  for (std::int64_t n = 0; n < nn; ++n) {
    const double mass = m.mass[n];
    const Vec3 v0 = m.v[n];
    Vec3 f = m.f[n] + mass * gravity;
    const double al = m.local_damping[n];
    Vec3 fd{};
    if (al > 0) {
      // Local damping (Cundall): opposes the velocity with a fraction of the unbalanced force.
      for (int k = 0; k < 3; ++k) fd[k] = -al * std::abs(f[k]) * (v0[k] > 0 ? 1.0 : (v0[k] < 0 ? -1.0 : 0.0));
      f += fd;
    }
    const double cdt = 0.5 * m.damping[n] * dt;
    const Vec3 v1 = ((1.0 - cdt) * v0 + (dt / mass) * f) / (1.0 + cdt);
    m.v[n] = v1;
    const Vec3 vmid = 0.5 * (v0 + v1);
    // Viscous: c m |v_mid|^2 dt; local: -F_d . v_mid dt.
    dissipated[n] += dt * (m.damping[n] * mass * dot(vmid, vmid) - dot(fd, vmid));
    if (ke) ke[n] = 0.5 * mass * dot(vmid, vmid);
  }
}

void update_positions(Model& m, double dt) {
  const auto nn = static_cast<std::int64_t>(m.n_nodes());
#pragma omp parallel for schedule(static)
  for (std::int64_t n = 0; n < nn; ++n) m.x[n] += dt * m.v[n];
}

}  // namespace cdem
