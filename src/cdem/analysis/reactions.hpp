// Reaction forces of the velocity constraints (fixed, roller and prescribed-velocity boundaries)
// per face set, for reactions.csv (lab tests such as the Brazilian disc are measured by them).
//
// A constraint changes the free velocity v_free of the step to v_c; the support's force on the
// body is then R = M (v_c - v_free) / dt (M the mass of the node, or in tied mode of its vertex
// cluster, which is constrained as a whole). The kernels (integrate.cpp: integrate_blocks and
// apply_constraints, integrate_clusters) do not keep R; this meter recomputes v_free after the
// step from the same update (the node's or cluster's force m.f, which the step leaves in place,
// gravity, viscous and local damping, v(n-1/2) saved before the step) and applies each
// boundary's constraints in the kernels' order (node by node, boundaries in file order), adding
// each change of velocity to the boundary that made it. The recomputed constrained velocity is
// the kernel's to rounding (the sum over boundaries is the total reaction). Only the (few)
// constrained nodes are visited. If the integrator's update changes, this must follow it: the
// test ReactionForces.* compares the recomputed velocities with the kernel's.
#pragma once
#include <string>
#include <vector>

#include "cdem/model/boundary_spec.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/boundaries.hpp"

namespace cdem {

class ReactionMeter {
 public:
  // The case's boundaries and gravity, as given to the solver's prepare_boundaries (`where`
  // names the case file in its messages).
  ReactionMeter(const Model& m, const std::vector<BoundaryCondition>& boundaries, Vec3 gravity,
                const std::string& where);

  bool empty() const { return sets_.empty(); }
  // The face sets with a velocity constraint, in the order of their first [[boundary]].
  const std::vector<std::string>& face_sets() const { return sets_; }

  // Before Simulation::step: keeps v(n-1/2) of the constrained nodes (and in tied mode of every
  // node of their vertices).
  void before_step(const Model& m);
  // The nodes before_step reads (the halo stage of a distributed run gathers their velocities).
  const std::vector<std::int32_t>& watched_nodes() const { return nodes_; }
  // After it: the reactions of that step, per face set (N), with t_mid = t_n + dt / 2 (the time
  // the prescribed velocities were taken at). Returns the largest difference between a
  // recomputed constrained velocity and the kernel's (m/s), a check on the recomputation.
  double after_step(const Model& m, double dt, double t_mid);
  const std::vector<Vec3>& forces() const { return force_; }

 private:
  Vec3 gravity_;
  std::vector<std::string> sets_;
  std::vector<Boundaries> bcs_;        // one per constraint [[boundary]], in file order
  std::vector<std::int32_t> bc_set_;   // its face set's index in sets_
  std::vector<std::int32_t> nodes_;    // nodes whose v(n-1/2) is kept (ascending)
  std::vector<Vec3> v_old_;            // their v(n-1/2)
  std::vector<std::int32_t> vertices_; // tied mode: the vertices with a constrained node
  std::vector<std::uint8_t> constrained_;  // per node: 1 if some boundary constrains it
  std::vector<Vec3> force_;
};

}  // namespace cdem
