// Interface spring points (SPEC 1.3, eq. 7): per spring point joining node a (block A) and
// node b (block B), with n the unit normal of the interface (average of the two current face
// normals, pointing from A to B):
//   normal force   F_n = k_n A_c (d_n + g0 - w - d_dil),  d_n = (x_b - x_a) . n  (tension
//                  positive; g0 the offset that carries an initial in-situ normal force)
//   shear force    F_s += k_s A_c du_s, du_s the tangential part of the objective relative
//                  displacement increment (v_b - v_a) dt - d_n (n - n_old): the spin of the
//                  interface carrying the gap d_n along is removed, so a rigid rotation adds no
//                  shear (n_old is the normal of the previous call, kept per interface in
//                  Model::iface_normal: the previous positions are x - v dt up to rounding; the
//                  first call, Model::iface_normal_set false, rebuilds it from x - v dt); F_s is
//                  kept in the current tangent plane (rotated with the interface, magnitude
//                  preserved). A caller that moves nodes other than by x += v dt between calls
//                  clears iface_normal_set.
// The normal force is written in total form (the relative displacement of the two coincident
// nodes along the current normal): for intact springs this equals the incremental update of
// eq. (7) for any rigid motion and does not drift; for broken springs it makes contact
// re-engage exactly when the faces touch again.
// Laws: brittle Mohr-Coulomb with tension cut-off, fracture energy (linear softening, one
// damage D = max(w / w_c, s / s_c) shared by both strengths), elastic (unbreakable).
// After breaking: compression only and Coulomb friction |F_s| <= -F_n tan(phi_r); a broken
// pair whose nodes have separated by more than release_distance is released (no force).
// Dissipated energy per spring point: the work done on it minus the change of its elastic
// energy F_n^2 / (2 k_n) + |F_s|^2 / (2 k_s), accumulated with the trapezoidal rule. An intact
// spring point under a linear law (elastic, Mohr-Coulomb before breaking) dissipates nothing,
// so spring_forces skips that book-keeping on its fast path; the step in which it breaks
// accounts for the released energy.
#pragma once
#include <cstdint>

#include "cdem/model/model.hpp"

namespace cdem {

struct SpringPoint {
  double kn, ks, area;          // stiffness x A_c (N/m), A_c (m^2)
  double fn;                    // N
  Vec3 fs;                      // N
  double w, slip, dil;          // m
  std::uint8_t state, mode;
  float break_time;
  double dissipated;            // J
  double g0 = 0;                // normal offset (m): F_n = k_n A_c (d_n + g0 - w - d_dil); set by
                                // an initial (in-situ) stress, F_n0 / (k_n A_c)
};

// Updates one spring point. d = x_b - x_a, du = the objective relative displacement increment
// (see above), n the unit normal, t the current time, release_distance in m. Returns the force
// on node a (b gets minus it).
Vec3 update_spring_point(SpringPoint& sp, const SpringLaw& law, Vec3 d, Vec3 du, Vec3 n, double t,
                         double release_distance, Vec3 force_old);

// All spring points: sp_force[s] = force on node a. Parallel over interfaces.
void spring_forces(Model& m, double dt, double t);

// Adds the spring forces to the nodes through the node -> spring list (fixed order: bitwise
// identical sums for any thread count). Parallel over nodes.
void gather_spring_forces(Model& m);

// The same for nodes [n0, n1): f[n] += (sum of its spring forces, in the list's order). The
// block kernels call it for their own nodes right after assigning them (block_forces with
// gather_springs), which saves a pass over f and a parallel region per step.
inline void add_spring_forces(Model& m, std::int64_t n0, std::int64_t n1) {
  for (std::int64_t n = n0; n < n1; ++n) {
    Vec3 acc{};
    for (auto k = m.node_sp_offset[n]; k < m.node_sp_offset[n + 1]; ++k) {
      const auto e = m.node_sp_list[k];
      if (e > 0)
        acc += m.sp_force[e - 1];
      else
        acc -= m.sp_force[-e - 1];
    }
    m.f[n] += acc;
  }
}

}  // namespace cdem
