// Stable time step (SPEC 1.1):
//   dt = safety * min( min over blocks h_e / c_p , min over nodes sqrt(2 m_i / sum k_n A_c) )
// h_e is the block's smallest altitude; the spring limit uses the normal stiffnesses of the
// spring points attached to node i. The limiting part is reported.
#pragma once
#include <cstdint>
#include <string>

#include "cdem/model/model.hpp"

namespace cdem {

struct StableStep {
  double dt_block = 0;       // min h_e / c_p (s), before the safety factor
  double dt_spring = 0;      // min sqrt(2 m / sum k_n A_c) (s)
  std::int64_t block = -1;   // the limiting block
  std::int64_t node = -1;    // the limiting node (spring limit)
  double dt = 0;             // safety * min
  double safety = 0;         // the safety factor applied
  std::string limit;         // "blocks" or "springs"
};

// With contact_share, every node counts one more spring of the mean stiffness of its own spring
// points: the general contact's penalty in springs mode (physics/contact.hpp), so that a node
// with all its springs and a contact stays within the step.
StableStep stable_time_step(const Model& m, double safety, bool contact_share = false);

// The largest eigenvalue omega_e^2 of M_e^-1 K_e of block b (1/s^2): its linear stiffness at the
// reference configuration, K_e = sum over integration points w_q B^T D B (the kernels' Lame
// constants and reference gradients), with its lumped nodal masses M_e. The free element's
// highest frequency.
double block_omega2(const Model& m, std::size_t b);

// Tied mode (physics/ties.hpp): by the element eigenvalue theorem (Irons; Hughes, The Finite
// Element Method, 2000, sec. 9.3), the assembled system of the clusters (whose masses are sums
// of the blocks' lumped masses) has omega_max^2 <= max_e omega_e^2 over the elastic blocks, so
// central differences are stable for dt <= 2 / omega_max (dt_block). The opened points' springs
// take at most the share eta of omega_max^2 (set_opened_stiffness), so
//   dt = safety * 2 / (omega_max sqrt(1 + eta))      (dt_spring reports 2 / (omega_max sqrt(eta))).
// `omega2_max` returns omega_max^2.
StableStep stable_time_step_tied(const Model& m, double safety, double eta, double* omega2_max);

// Mass scaling of the few blocks that would set the step (tied mode; docs/theory.md "Mass scaling
// of the smallest blocks"). A Gmsh tet mesh holds a few slivers whose own highest frequency is
// several times that of the well-shaped tets of the same size; the step follows them. Each rock
// block whose free-element bound 2 / omega_e is below `bound` gets its nodes' masses multiplied by
// s = (bound omega_e / 2)^2, so that its bound is `bound` (omega_e^2 scales as 1 / s); the other
// blocks are untouched. The element eigenvalue theorem then bounds the whole model by `bound`.
// Explosive blocks and blocks holding a bar's charge are skipped. Returns what was added.
struct MassScaling {
  double bound = 0;          // the element bound asked (s), 0: no scaling
  std::int64_t blocks = 0;   // blocks made heavier
  double added = 0;          // kg (per unit thickness in 2D) added
  double total = 0;          // the model's mass before (same unit)
  double max_factor = 1;     // the largest s
  double share() const { return total > 0 ? added / total : 0.0; }
};
MassScaling scale_masses_to_bound(Model& m, double bound);
// The free-element bounds 2 / omega_e of the rock blocks (those stable_time_step_tied takes):
// the smallest and the 0.1 %, 1 % and 10 % quantiles, for check (choosing mass_scaling_dt).
struct BoundQuantiles {
  double min = 0, q001 = 0, q01 = 0, q1 = 0;
};
BoundQuantiles block_bound_quantiles(const Model& m);

// One line for check and the run's log: how many blocks, how much mass, the largest factor.
std::string describe_mass_scaling(const MassScaling& ms, double dt_asked, int dim);

}  // namespace cdem
