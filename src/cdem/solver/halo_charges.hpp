// The bar charges of a distributed run's halo stage (docs/parallel.md, "Charges in the halo
// stage").
//
// No part holds a whole charge: a bar's bound blocks, and the cracks its gas fills, may lie in
// several parts. But a charge's state is small: per segment its burnt fraction and pressure,
// per deck one gas body, per interface the gas has reached its fill. So every rank keeps that
// state for the whole model (the BarCharges of the whole model, built by the same set-up on
// every rank) and steps it, the same bits on every rank, from the inputs one process would read:
//   - each bound block's volume ratio, formed by the block's owner (its block kernel);
//   - the crack list of the step: each open interface that the gas pass could act on
//     (gas_candidate), with its aperture, formed by the interface's owner.
// Those inputs are gathered from every rank in one MPI_Allgatherv per step. The state step
// (bar_state, gas_state with the given list) then runs on every rank over the whole model's
// topology. Each part applies the loads of that state to its own and ghost blocks: the gas's crack
// faces (in the whole list's order), then each bound block inflated by its pressure. So its own
// nodes get the forces one process gives them, bit for bit. The loads' power terms are summed
// exactly over the ranks by the step's sums (Simulation::step_sums), each from the rank owning
// the load (AppliedLoads::Owned).
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/explosive/charges.hpp"
#include "cdem/model/model.hpp"
#include "cdem/parallel/halo.hpp"
#include "cdem/physics/applied_loads.hpp"

namespace cdem {

class HaloBars {
 public:
  // `bars`: the whole model's charges (their state is stepped here); `whole`: the whole model
  // (its topology and sizes); `pm`: this rank's part's indices, `local` its model (as set up);
  // `part`: the rank of each whole block.
  HaloBars(BarCharges& bars, const Model& whole, const PartModel& pm, const Model& local,
           const std::vector<std::int32_t>& part, int rank);
  // The step's explosive loads at time t on the part's model `local` (a load hook).
  void load(Model& local, AppliedLoads& out, double t);

 private:
  BarCharges& bars_;
  const Model& whole_;
  std::vector<std::int32_t> iface_;                   // local -> global
  std::vector<std::uint8_t> own_block_, own_iface_;   // per local entity
  std::vector<std::int32_t> elem_local_;              // per bound block (bars.elem_block): local block, -1
  std::vector<std::pair<std::int32_t, std::int32_t>> own_elems_;  // (bound block index, local block)
  bool cracks_ = false;
  // per step (kept between steps: no allocation once grown)
  std::vector<double> vol_ratio_;  // per whole block (only the bound blocks' are read)
  std::vector<double> mine_, all_;
  std::vector<std::int64_t> at_;
  std::vector<std::pair<std::int32_t, std::int32_t>> order_;  // (interface, place in all_)
  CrackInputs given_;
  std::int32_t local_iface(std::int32_t global) const;
};

}  // namespace cdem
