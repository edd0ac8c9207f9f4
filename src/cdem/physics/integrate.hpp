// Explicit central-difference update (SPEC 1.1) with gravity, mass-proportional viscous
// damping (eq. 3, semi-implicit so that it is stable for any c dt) and local non-viscous
// damping F_d = -alpha_L |F| sign(v) per component:
//   v(n+1/2) = [(1 - c dt/2) v(n-1/2) + dt (F + F_d + m g) / m] / (1 + c dt/2)
// The energy dissipated by both dampings over the step is accumulated per node into
// `dissipated` (J). With `ke` non-null, the kinetic energy at t_n, 1/2 m |v_mid|^2 with
// v_mid = (v(n-1/2) + v(n+1/2)) / 2, is written per node.
// An empty Model::damping or Model::local_damping means zero for every node (see
// release_zero_damping); `dissipated` is then left untouched when both are empty.
#pragma once
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

void integrate(Model& m, Vec3 gravity, double dt, std::vector<double>& dissipated, double* ke);

// Releases Model::damping and Model::local_damping when they are zero at every node (the usual
// case: no damping zone, undamped materials): 16 B per node less, and integrate skips them.
void release_zero_damping(Model& m);

// x(n+1) = x(n) + dt v(n+1/2)
void update_positions(Model& m, double dt);

}  // namespace cdem
