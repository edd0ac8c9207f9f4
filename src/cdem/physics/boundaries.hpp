// Boundary conditions (SPEC 1.4) prepared once from their specs (boundary_spec.hpp): velocity constraints (fixed,
// roller, prescribed velocity) applied after the velocity update, and boundary forces
// (pressure, Lysmer-Kuhlemeyer viscous dashpots) added before it. Gravity is applied in the
// integration kernel. The boundary forces run in parallel (per facet, then per node in a fixed
// order); the constraints and the work sums are small and serial.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "cdem/model/boundary_spec.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

struct Boundaries {
  struct Constraint {
    std::int32_t node;
    std::uint8_t kind;  // 0 fixed, 1 roller (normal), 2 prescribed velocity
    Vec3 dir;           // roller: unit normal; velocity: velocity vector (m/s)
    std::int32_t table; // velocity: index into tables
    std::int32_t slot;  // index into work_nodes
  };
  struct LoadFacet {
    Model::BoundaryFacet facet;
    std::uint8_t kind;   // 0 pressure, 1 dashpot
    double a, b;         // pressure: value (Pa); dashpot: rho c_p, rho c_s (Pa s/m)
    std::int32_t table;
    std::array<std::int32_t, 3> slot;  // index of each facet node in work_nodes
  };
  std::vector<Constraint> constraints;
  std::vector<LoadFacet> loads;
  std::vector<TimeTable> tables;
  Vec3 gravity{};
  // Energy book-keeping on the (few) boundary nodes: v(n-1/2), so that the work of the step's
  // load and dashpot forces (summed again from load_force by load_work_terms) uses the mid-step
  // velocity (v_old + v_new) / 2.
  std::vector<std::int32_t> work_nodes;
  std::vector<Vec3> v_old;
  // Per work node, its load-facet contributions in the serial order (facet by facet, node q of
  // each): entries load * 3 + q of load_force, node_load_offset being a CSR offset (size
  // work_nodes + 1). Every node's force is summed in this order whatever the thread count.
  std::vector<std::int32_t> node_load_offset, node_load_entry;
  std::vector<Vec3> load_force;  // per load facet and node q, the step's force (3 per facet)
  std::vector<double> work_terms;  // load_work_terms's four per work node (grown once)
  // The constraints ordered by node (then by their order in `constraints`): con_node[k] is the
  // node of constraints[con_order[k]] (constrain_velocity's binary search; tied mode).
  std::vector<std::int32_t> con_node, con_order;
};

// Applies every constraint of node n, in their order, to the velocity v (prescribed values at
// time t); v unchanged when the node has none.
Vec3 constrain_velocity(const Boundaries& b, std::int32_t n, Vec3 v, double t);

// The constraints and loads of `bcs` on m (a boundary's index in bcs names its key,
// boundary[k]), with the gravity the integration applies. Throws InputError naming `where`
// (the case file) and the key for an unknown face set.
Boundaries prepare_boundaries(const Model& m, const std::vector<BoundaryCondition>& bcs,
                              Vec3 gravity, const std::string& where);

// Adds the pressure and dashpot forces at time t to m.f (and saves v(n-1/2) of boundary nodes).
void boundary_forces(Model& m, Boundaries& b, double t);

// Velocity constraints on v(n+1/2), prescribed values taken at t (= t_n + dt/2). `terms` is set,
// per constraint in order, to the two powers of its reaction R = m (v_c - v_free) / dt: R . v_mid
// and R . v(n+1/2). The step sums them (Simulation::step_sums): the reactions' work over the
// step, dt sum R . v_mid, and its part after t_n, dt/2 sum R . v(n+1/2) (Simulation::energy).
void apply_constraints(Model& m, Boundaries& b, double t, double dt, std::vector<double>& terms);

// The boundary loads' powers of the step into b.work_terms, four per work node: the pressure's
// and the dashpots' F . v_mid, and the same with v(n+1/2) (their parts after t_n). The step sums
// them: the loads' work dt sum F . v_mid (dashpots: absorbed, >= 0) and the parts after t_n.
void load_work_terms(const Model& m, Boundaries& b);

}  // namespace cdem
