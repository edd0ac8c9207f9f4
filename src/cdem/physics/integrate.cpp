#include "cdem/physics/integrate.hpp"

#include <cmath>

#include "cdem/core/loop_split.hpp"
#include "cdem/physics/boundaries.hpp"

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
        // The kinetic energy at t_n of the leapfrog invariant, 1/2 m v(n-1/2).v(n+1/2): with the
        // strain energy at x_n it is conserved exactly by the central-difference scheme in free
        // linear vibration (1/2 m |v_mid|^2 exceeds it by 1/8 m |v(n+1/2) - v(n-1/2)|^2, an
        // artefact of relative size (omega dt)^2 / 8 per mode; docs/theory.md).
        ke_b += 0.5 * mass * dot(v0, v1);
        // The part after t_n of the step's damping dissipation (c m v_mid - F_d) . v_mid dt: the
        // force times the displacement v(n+1/2) dt / 2 (Simulation::energy).
        if constexpr (kViscous || kLocal) cke_b += 0.5 * dt * dot(c * mass * vmid - fd, v1);
      }
    }
    if constexpr (kViscous || kLocal) dissipated[b] += diss_b;
    if (ke) {
      ke[b] = ke_b;
      if (cke) cke[b] = cke_b;
    }
  }
}

// Tied mode: one velocity per cluster (ties.hpp). Per cluster C (a run of its vertex's node
// list), in the node order of the list:
//   M = sum m_n, F = sum f_n + M g, c = sum c_n m_n / M, alpha = sum alpha_n m_n / M,
//   F_d = -alpha |F| sign(v) per component, v(n+1/2) = [(1 - c dt/2) v(n-1/2) + dt (F + F_d) / M]
//   / (1 + c dt/2), then the constraints of every node of C, node by node, each in its order
//   (a cluster is fixed, rolled or driven wherever one of its nodes is), and v(n+1/2) copied to
//   every node of C. Reaction work of the constraints: M (v_c - v_free) / dt . v_mid dt.
// Per vertex (each vertex summed in order by one thread: bitwise the same for any thread count)
// the dissipation, kinetic energy, c ke and reaction work, as integrate_blocks per block.
template <bool kViscous, bool kLocal>
void integrate_clusters(Model& m, const Boundaries& bc, double dt, double t_mid,
                        const std::uint8_t* vtx_con, double* dissipated, double* ke, double* cke,
                        double* reaction) {
  const auto nv = static_cast<std::int64_t>(m.n_vertices());
  const std::int32_t* off = m.vtx_offset.data();
  const std::int32_t* nodes = m.vtx_nodes.data();
  const std::uint8_t* run = m.vtx_run.data();
  const Vec3 gravity = bc.gravity;
  // (a vertex inside the rock has some twenty nodes, one on its surface a few; a broken vertex's
  // nodes are clusters of their own: the cost per vertex varies along the model)
  static LoopSplit split;
  split.run(nv, [&](const LoopSplit::Range& part) {
    for (std::int64_t vx = part.lo; vx < part.hi; ++vx) {
      double ke_v = 0, cke_v = 0, diss_v = 0, react_v = 0, react_after_v = 0;
      const std::int32_t o1 = off[vx + 1];
      for (std::int32_t p = off[vx]; p < o1;) {
        std::int32_t q = p + 1;
        while (q < o1 && !run[q]) ++q;
        const ClusterSums sums = cluster_sums(m, nodes, p, q, kViscous, kLocal);
        const double mass = sums.mass, cm = sums.cm, am = sums.am;
        Vec3 f = sums.f;
        f += mass * gravity;
        const Vec3 v0 = m.v[nodes[p]];
        Vec3 fd{};
        if constexpr (kLocal) {
          const double al = am / mass;
          if (al > 0) {
            for (int c = 0; c < 3; ++c)
              fd[c] = -al * std::abs(f[c]) * (v0[c] > 0 ? 1.0 : (v0[c] < 0 ? -1.0 : 0.0));
            f += fd;
          }
        }
        Vec3 v1;
        double c = 0;
        if constexpr (kViscous) {
          c = cm / mass;
          const double cdt = 0.5 * c * dt;
          v1 = ((1.0 - cdt) * v0 + (dt / mass) * f) / (1.0 + cdt);
        } else {
          v1 = v0 + (dt / mass) * f;
        }
        if (vtx_con && vtx_con[vx]) {
          const Vec3 vfree = v1;
          for (std::int32_t k = p; k < q; ++k) v1 = constrain_velocity(bc, nodes[k], v1, t_mid);
          const Vec3 r = (mass / dt) * (v1 - vfree);
          react_v += dot(r, 0.5 * (v0 + v1)) * dt;
          react_after_v += 0.5 * dt * dot(r, v1);
        }
        for (std::int32_t k = p; k < q; ++k) m.v[nodes[k]] = v1;
        const Vec3 vmid = 0.5 * (v0 + v1);
        if constexpr (kViscous || kLocal) diss_v += dt * (c * mass * dot(vmid, vmid) - dot(fd, vmid));
        if (ke) {
          ke_v += 0.5 * mass * dot(v0, v1);  // the leapfrog invariant's, as integrate_blocks
          if constexpr (kViscous || kLocal) cke_v += 0.5 * dt * dot(c * mass * vmid - fd, v1);
        }
        p = q;
      }
      if constexpr (kViscous || kLocal) dissipated[vx] += diss_v;
      if (ke) {
        ke[vx] = ke_v;
        if (cke) cke[vx] = cke_v;
      }
      reaction[2 * vx] = react_v;
      reaction[2 * vx + 1] = react_after_v;
    }
  });
}

}  // namespace

void integrate_tied(Model& m, const Boundaries& bc, double dt, double t_mid,
                    const std::uint8_t* vtx_con, double* dissipated, double* ke, double* cke,
                    double* reaction) {
  const bool viscous = !m.damping.empty(), local = !m.local_damping.empty();
  if (viscous && local)
    integrate_clusters<true, true>(m, bc, dt, t_mid, vtx_con, dissipated, ke, cke, reaction);
  else if (viscous)
    integrate_clusters<true, false>(m, bc, dt, t_mid, vtx_con, dissipated, ke, cke, reaction);
  else if (local)
    integrate_clusters<false, true>(m, bc, dt, t_mid, vtx_con, dissipated, ke, cke, reaction);
  else
    integrate_clusters<false, false>(m, bc, dt, t_mid, vtx_con, dissipated, ke, cke, reaction);
}

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
