// The halo stage of a distributed run (issue 17; docs/parallel.md "The halo stage"): each rank
// steps a model of its own part and a ghost zone around it, instead of the whole model.
//
// Ownership: a block belongs to one part (partition_kway or block_ranges, partition.hpp); its
// nodes belong to it too. A part's local model holds its own blocks and the ghost zone: every
// block that shares a mesh vertex with one of its own (one ring). A tied vertex cluster of one of
// its own nodes (ties.hpp) then has all its nodes in the local model, and so have the spring
// points acting on them (a point lies on a face through the vertex, and both blocks of that face
// share the vertex): the cluster's sum of forces and masses is the whole model's, in the same
// order. A ghost node's spring-point count, from which the opened points' stiffness is set
// (set_opened_stiffness: the least over an interface's nodes), is the whole model's only if every
// face of its block is in the part; it is handed to the part's set-up from the whole model
// instead (node_spring_counts, WholeModelSetup::node_springs). Until 7 Dec 2026 a second ring (the
// face neighbours of the first) made those counts whole, and made a part step 1.3-2 times more
// ghosts.
// The local model is cut from the set-up-ready model (build_model's, before Simulation) keeping
// the global order of blocks, nodes, interfaces and vertices, so every sum the kernels form over
// a node, a block or a cluster runs over the same terms in the same order as in the whole model:
// a part's own nodes get the whole model's bits, step after step, provided that before each step
// its ghost nodes' positions and velocities are the whole model's (their owners'; the ghosts'
// own forces are incomplete, their motion is not computed here but received).
//
// Verified by tests/verification/test_halo.cpp (ghosts copied from a whole-model run) and
// tests/mpi/test_halo_mpi.cpp (ghosts received over MPI); the run uses it through
// solver/simulation_halo.cpp (the parts' own entities for the exact sums, the gathers) and
// run.cpp; the bar charges through solver/halo_charges.hpp. Not yet: contact, solid charges
// (docs/parallel.md, the plan).
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// The local model of a part and the global index of each of its entities.
struct PartModel {
  Model model;
  std::vector<std::int32_t> block;   // global block of each local block (ascending)
  std::vector<std::int32_t> node;    // global node of each local node (ascending)
  std::vector<std::int32_t> iface;   // global interface of each local interface (ascending)
  std::vector<std::int32_t> vertex;  // global mesh vertex of each local vertex (ascending)
  std::vector<std::uint8_t> own;     // per local block: 1 own, 0 ghost
  std::vector<std::int32_t> ghost_nodes;  // local nodes of the ghost blocks (ascending)
  std::size_t own_blocks = 0, ghost_blocks = 0;
};

// Per interface of the part `pm` (its model `local`, pm.model or the one set up from it): 1 when
// part p owns it. An interface belongs to the part of its block A.
std::vector<std::uint8_t> own_interfaces(const PartModel& pm, const Model& local, const std::vector<std::int32_t>& part,
                                         std::int32_t p);

// Per node of the part `pm`, the whole model's count of its spring points (the part's set-up:
// WholeModelSetup::node_springs).
std::vector<std::int32_t> node_spring_counts(const Model& whole, const PartModel& pm);

// The blocks of part p (part: a part per block) and of its ghost zone (the ring above), as
// ascending global block indices, and per entry whether it is p's own.
void part_blocks(const Model& m, const std::vector<std::int32_t>& part, std::int32_t p,
                 std::vector<std::int32_t>& blocks, std::vector<std::uint8_t>& own);

// The local model of part p of `m`, a model as build_model made it (not yet set up by a
// Simulation: no ties). Throws std::logic_error for a tied model.
PartModel cut_part(const Model& m, const std::vector<std::int32_t>& part, std::int32_t p);

// The ghosts' motion from their owners: each step, every part sends the positions and
// velocities of its own nodes that other parts hold as ghosts, and receives its ghosts' (one
// message each way per neighbouring part). The lists are built at set-up: each part asks the
// owner of each of its ghost nodes for it (all_to_all, parallel/ranks.hpp), in ascending global
// node order, and the owner sends in the order asked. Needs MPI with more than one part.
class HaloExchange {
 public:
  // This rank's part (rank r's part is r) and its local model.
  HaloExchange(const PartModel& pm, const std::vector<std::int32_t>& part);
  // x and v of the ghost nodes of `local` (pm's model, stepped) from their owners.
  void exchange(Model& local);
  const std::vector<int>& peers() const { return peers_; }
  std::size_t nodes_sent() const;
  std::size_t nodes_received() const;

 private:
  std::vector<int> peers_;                          // neighbouring parts, ascending
  std::vector<std::vector<std::int32_t>> send_, recv_;  // per peer: local nodes
  std::vector<std::vector<double>> sbuf_, rbuf_;
};

}  // namespace cdem
