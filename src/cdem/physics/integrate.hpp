// Explicit central-difference update (SPEC 1.1) with gravity, mass-proportional viscous
// damping (eq. 3, semi-implicit so that it is stable for any c dt) and local non-viscous
// damping F_d = -alpha_L |F| sign(v) per component:
//   v(n+1/2) = [(1 - c dt/2) v(n-1/2) + dt (F + F_d + m g) / m] / (1 + c dt/2)
// Per block (its nodes are contiguous; the loop runs over blocks, each summing its nodes in
// order: bitwise the same for any thread count):
//   dissipated[b] += the energy both dampings dissipated at its nodes over the step (J);
//   with `ke` non-null, ke[b] = the kinetic energy at t_n of the leapfrog invariant, the sum of
//   1/2 m v(n-1/2).v(n+1/2), and, with `cke` non-null too, cke[b] = the part after t_n of the
//   step's damping dissipation, sum of 1/2 dt (c m v_mid - F_d) . v(n+1/2) with
//   v_mid = (v(n-1/2) + v(n+1/2)) / 2 (c the viscous coefficient): see Simulation::energy.
// An empty Model::damping or Model::local_damping means zero for every node (see
// release_zero_damping); `dissipated` is then not read (may be null) when both are empty.
#pragma once
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// The sums over one tied cluster's nodes nodes[p..q) (they move as one): its mass, the force on
// it, and its mass-weighted viscous and local damping coefficients (with `viscous` / `local`
// false, those stay 0 and their arrays are not read). The cluster integration and the reaction
// forces (analysis/reactions.cpp) both take them from here, so the reactions are formed from the
// same sums in the same order (to rounding: the two files are compiled alike, but GCC may fuse a
// product into a multiply-add in one and not in the other).
struct ClusterSums {
  double mass = 0, cm = 0, am = 0;
  Vec3 f{};
};
inline ClusterSums cluster_sums(const Model& m, const std::int32_t* nodes, std::int32_t p,
                                std::int32_t q, bool viscous, bool local) {
  ClusterSums s;
  for (std::int32_t k = p; k < q; ++k) {
    const std::int32_t n = nodes[k];
    s.mass += m.mass[n];
    s.f += m.f[n];
    if (viscous) s.cm += m.damping[n] * m.mass[n];
    if (local) s.am += m.local_damping[n] * m.mass[n];
  }
  return s;
}

void integrate(Model& m, Vec3 gravity, double dt, double* dissipated, double* ke,
               double* cke = nullptr);

struct Boundaries;

// Tied mode (ties.hpp): the same update with one velocity per vertex cluster, the velocity
// constraints of the cluster's nodes applied to it (prescribed values at t_mid = t_n + dt/2),
// then copied to its nodes (integrate.cpp). Per vertex: dissipated[v] += the damping
// dissipation, with `ke` non-null ke[v] (and cke[v]) as above, reaction[2 v] = the work of the
// constraint reactions over the step and reaction[2 v + 1] its part after t_n,
// 1/2 dt R . v(n+1/2). vtx_con[v] != 0 marks the vertices with a constrained
// node (null: none).
void integrate_tied(Model& m, const Boundaries& bc, double dt, double t_mid,
                    const std::uint8_t* vtx_con, double* dissipated, double* ke, double* cke,
                    double* reaction);

// Releases Model::damping and Model::local_damping when they are zero at every node (the usual
// case: no damping zone, undamped materials): 16 B per node less, and integrate skips them.
void release_zero_damping(Model& m);

// x(n+1) = x(n) + dt v(n+1/2)
void update_positions(Model& m, double dt);

}  // namespace cdem
