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
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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

// The elastic branch of the fracture-energy law for an intact point with damage state (w,
// slip), this step's F_n = k_n A_c (d_n + g0 - d_dil - w) and |F_s|^2 after the step's
// increment: true when update_spring_point would neither soften it nor break it, so that F_n and
// F_s are its whole result (the springs mode's fast path, springs.cpp; test_fe_elastic.cpp).
// Its arithmetic on plain values (w_c, s_c, f_t A_c, c A_c, tan phi), for the vectorised loop
// (called where multiply-add contraction is off: springs.cpp, test_fe_elastic.cpp).
inline bool fe_elastic(double wc, double sc, double ftA, double cA, double tan_phi, double w,
                       double slip, double fn, double fs2) {
  const double dt_w = wc > 0 ? w / wc : (w > 0 ? 1.0 : 0.0);
  const double ds_s = sc > 0 ? slip / sc : (slip > 0 ? 1.0 : 0.0);
  const double dmg = std::max(dt_w, ds_s);
  const double ft_now = ftA * (1.0 - dmg);
  const double tau = std::max(0.0, cA * (1.0 - dmg) - fn * tan_phi);
  return !(fn > ft_now) & !(std::sqrt(fs2) > tau) & (dmg < 1.0);
}
inline bool fe_elastic(const SpringLaw& law, double area, double w, double slip, double fn, double fs2) {
  return fe_elastic(law.wc, law.sc, law.ft * area, law.c * area, law.tan_phi, w, slip, fn, fs2);
}

// All spring points: sp_fn, sp_fs (the force on node a is spring_force). Parallel over
// interfaces; vectorised over chunks of interfaces (springs.cpp) once the previous normals are
// kept, with the same arithmetic as spring_forces_reference. Tied mode (Model::tied): the active
// interfaces only, in chunks of that list, tied points skipped.
// [lo, hi): only these entries of the list the mode steps (tied mode: Model::active_ifaces;
// springs mode: the interfaces), a rank's share of a distributed run; each interface's results
// are the same bits whatever the range.
void spring_forces(Model& m, double dt, double t, std::int64_t lo = 0,
                   std::int64_t hi = std::numeric_limits<std::int64_t>::max());

// What spring_forces writes of an interface, packed for a distributed run's exchange
// (parallel/ranks.hpp): its normal and, per spring point, F_n, F_s, state, break mode, break
// time, dissipated work, and the fracture-energy state when kept (sp_w not empty). Every value
// converts to a double and back exactly. spring_state_doubles: the doubles per interface.
int spring_state_doubles(const Model& m);
// The interfaces list[k] for k in [lo, hi) (list null: interface k) into `out` / from `in`.
void pack_spring_state(const Model& m, const std::int32_t* list, std::int64_t lo, std::int64_t hi,
                       double* out);
void unpack_spring_state(Model& m, const std::int32_t* list, std::int64_t lo, std::int64_t hi,
                         const double* in);

// The same one interface and one spring point at a time (the reference form the vectorised
// kernel reproduces bit for bit, in both modes; test_spring_kernel.cpp).
void spring_forces_reference(Model& m, double dt, double t);

// The force of spring point s on its node a (node b gets minus it): F_n n + F_s, with n the
// interface normal of the last spring_forces call.
inline Vec3 spring_force(const Model& m, std::size_t s) {
  return m.sp_fn[s] * m.iface_normal[s / static_cast<std::size_t>(m.springs_per_iface)] +
         m.sp_fs[s];
}

// Adds the spring forces of block b's interfaces to its nodes: f[n] += (sum of the node's spring
// forces, in ascending spring order). Each interface gives one spring point per face node, so the
// sum of each node is in a fixed order: bitwise identical for any thread count. The block
// kernels call it for their block right after assigning its forces (block_forces with
// gather_springs), which saves a pass over f and a parallel region per step.
inline void add_spring_forces(Model& m, std::int32_t b) {
  if (m.tied && !m.block_active[b]) return;  // tied mode: only ties at this block, no force
  const std::int32_t n0 = m.block_first_node[b];
  const int nn = m.block_first_node[b + 1] - n0;
  const int np = m.springs_per_iface;
  // One accumulator per node (x, y, z of node j at 3 j): the three spring points of an interface
  // side belong to three different nodes, so consecutive updates do not wait on each other.
  double acc[12] = {};
  for (auto k = m.block_iface_offset[b]; k < m.block_iface_offset[b + 1]; ++k) {
    const std::int32_t e = m.block_iface_list[k];
    const bool a_side = e > 0;
    const std::int64_t s0 = static_cast<std::int64_t>((a_side ? e : -e) - 1) * np;
    const Vec3 n = m.iface_normal[s0 / np];
    const std::int32_t* node = (a_side ? m.sp_a.data() : m.sp_b.data()) + s0;
    for (int q = 0; q < np; ++q) {
      const Vec3 f = m.sp_fn[s0 + q] * n + m.sp_fs[s0 + q];
      double* a = acc + 3 * (node[q] - n0);
      if (a_side) {
        a[0] += f.x; a[1] += f.y; a[2] += f.z;
      } else {
        a[0] -= f.x; a[1] -= f.y; a[2] -= f.z;
      }
    }
  }
  for (int j = 0; j < nn; ++j) m.f[n0 + j] += Vec3{acc[3 * j], acc[3 * j + 1], acc[3 * j + 2]};
}

// The same for every block, parallel over blocks (tests and benchmarks; the step fuses it into
// the block kernels).
void gather_spring_forces(Model& m);

// Calls fn(s) for every spring point at block b's nodes (its interfaces' spring points).
template <class Fn>
void for_each_block_spring(const Model& m, std::int32_t b, Fn&& fn) {
  const int np = m.springs_per_iface;
  for (auto k = m.block_iface_offset[b]; k < m.block_iface_offset[b + 1]; ++k) {
    const std::int32_t e = m.block_iface_list[k];
    const std::size_t s0 = static_cast<std::size_t>((e > 0 ? e : -e) - 1) * np;
    for (int q = 0; q < np; ++q) fn(s0 + q);
  }
}

// Drops the fracture-energy state arrays (sp_w, sp_slip, sp_dil) when no interface law is the
// fracture-energy law and they are all zero: the other laws never change them (Simulation calls
// it; the kernels read them as 0 then).
void release_unused_spring_state(Model& m);

}  // namespace cdem
