// Explicit central-difference update (SPEC 1.1) with gravity, mass-proportional viscous
// damping (eq. 3, semi-implicit so that it is stable for any c dt) and local non-viscous
// damping F_d = -alpha_L |F| sign(v) per component:
//   v(n+1/2) = [(1 - c dt/2) v(n-1/2) + dt (F + F_d + m g) / m] / (1 + c dt/2)
// Per block (its nodes are contiguous; the loop runs over blocks, each summing its nodes in
// order: bitwise the same for any thread count):
//   dissipated[b] += the energy both dampings dissipated at its nodes over the step (J);
//   with `ke` non-null, ke[b] = the kinetic energy at t_n, sum of 1/2 m |v_mid|^2 with
//   v_mid = (v(n-1/2) + v(n+1/2)) / 2, and, with `cke` non-null too, cke[b] = sum of c ke
//   (c the viscous coefficient; 2 dt cke is the step's viscous dissipation).
// An empty Model::damping or Model::local_damping means zero for every node (see
// release_zero_damping); `dissipated` is then not read (may be null) when both are empty.
#pragma once
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

void integrate(Model& m, Vec3 gravity, double dt, double* dissipated, double* ke,
               double* cke = nullptr);

// Releases Model::damping and Model::local_damping when they are zero at every node (the usual
// case: no damping zone, undamped materials): 16 B per node less, and integrate skips them.
void release_zero_damping(Model& m);

// x(n+1) = x(n) + dt v(n+1/2)
void update_positions(Model& m, double dt);

}  // namespace cdem
