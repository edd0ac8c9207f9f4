// Stiffness-proportional (Rayleigh beta) damping of the blocks (docs/theory.md "Stiffness-
// proportional damping"): a viscous stress
//   S_v = beta (lambda tr(E') I + 2 G E'),   E' = sym(R^T F'),   F' = sum_i v_i (x) grad_X N_i,
// in the block's co-rotated frame (R from the polar split of F, as the elastic kernels), nodal
// forces f_i = -V0 R S_v grad_X N_i. Its power is -V0 beta E':C:E' <= 0, and a rigid rotation
// (F' = W F, W skew) gives E' = sym(R^T W R U), zero at U = I: no damping of rigid motion.
// For the linear system the damping matrix is beta K, so a mode of frequency omega decays with
// the damping ratio zeta = beta omega / 2: the mesh's highest frequencies are damped most, the
// blast's wave band little. beta is per block material ([[material]] stiffness_damping), 0 for
// explosive groups (solid charges carry the products' pressure only).
#pragma once
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

// Adds the damping forces at the velocities v(n-1/2) to m.f (after block_forces assigned it).
// fd[n] receives node n's damping force (zero for undamped blocks), power[b] the block's
// sum fd . v at those velocities (<= 0). Both sized by the caller (n_nodes, n_blocks).
void stiffness_damping_forces(Model& m, std::vector<Vec3>& fd, std::vector<double>& power);

// The largest beta (s) over the materials of elastic blocks.
double max_stiffness_damping(const Model& m);

// Central differences with a damping force on v(n-1/2) are stable for a mode of frequency omega
// and damping ratio zeta when omega dt < 2 (sqrt(1 + zeta^2) - zeta) (docs/theory.md). With
// zeta = beta omega / 2 and dt_undamped = 2 / omega this is
//   dt < dt_undamped (sqrt(1 + zeta^2) - zeta),  zeta = beta / dt_undamped.
double damped_stable_step(double dt_undamped, double beta);

}  // namespace cdem
