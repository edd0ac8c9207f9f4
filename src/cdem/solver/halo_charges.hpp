// The charges of a distributed run's halo stage, bars and solid charges (docs/parallel.md,
// "Charges in the halo stage").
//
// No part holds a whole charge: a bar's bound blocks, a solid charge's explosive blocks, and the
// cracks their gas fills may lie in several parts. But a charge's state is small: per segment its
// burnt fraction and pressure, per explosive block its volume ratio, burnt fraction, pressure and
// collapse, per deck one gas body, per interface the gas has reached its fill. So every rank keeps
// that state for the whole model (the BarCharges and SolidCharges of the whole model, built by
// the same set-up on every rank) and steps it, the same bits on every rank, from the inputs one
// process would read:
//   - each bound block's volume ratio (its block kernel's) and each explosive block's
//     (current_volume_ratio), formed by the block's owner;
//   - the crack list of the step: each open interface that the gas pass could act on
//     (gas_candidate), with its aperture, formed by the interface's owner.
// Those inputs are gathered from every rank in one MPI_Allgatherv per step and kind of charge.
// The state step (bar_state; solid_gas_inputs, gas_state with the given list, solid_state) then
// runs on every rank over the whole model's topology. Each part applies the loads of that state
// to its own and ghost blocks, in one process's order: for the bars the gas's crack faces (in the
// whole list's order), then each bound block inflated by its pressure; for the solid charges the
// crack faces, then per explosive block in order its collapse (let_go_of_block: the same release
// in every part holding its interfaces), its stress and its inflation. So its own nodes get the
// forces one process gives them, bit for bit. The loads' power terms are summed exactly over the
// ranks by the step's sums (Simulation::step_sums), each from the rank owning the load
// (AppliedLoads::Owned).
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/explosive/charges.hpp"
#include "cdem/model/model.hpp"
#include "cdem/parallel/halo.hpp"
#include "cdem/physics/applied_loads.hpp"

namespace cdem {

class HaloCharges {
 public:
  // `bars`, `solids`: the whole model's charges (their state is stepped here); `whole`: the whole
  // model (its topology and sizes); `pm`: this rank's part's indices, `local` its model (as set
  // up); `part`: the rank of each whole block.
  HaloCharges(BarCharges& bars, SolidCharges& solids, const Model& whole, const PartModel& pm, const Model& local,
              const std::vector<std::int32_t>& part, int rank);
  // The step's explosive loads at time t on the part's model `local` (two load hooks, in one
  // process's order: the bars', then the solid charges').
  void load_bars(Model& local, AppliedLoads& out, double t);
  void load_solids(Model& local, AppliedLoads& out, double t);

 private:
  // Per kind of charge: its loaded blocks (bars.elem_block, solids.block) as local blocks (-1
  // not here), the owned ones (index, local block), and whether its gas fills cracks.
  struct Loaded {
    std::vector<std::int32_t> local;
    std::vector<std::pair<std::int32_t, std::int32_t>> own;
    bool cracks = false;
  };
  Loaded bars_at_, solids_at_;
  BarCharges& bars_;
  SolidCharges& solids_;
  const Model& whole_;
  std::vector<std::int32_t> iface_;                   // local -> global
  std::vector<std::uint8_t> own_block_, own_iface_;   // per local entity
  // per step (kept between steps: no allocation once grown)
  std::vector<double> vol_ratio_;  // per whole block (only the bound blocks' are read)
  std::vector<double> mine_, all_;
  std::vector<std::int64_t> at_;
  std::vector<std::pair<std::int32_t, std::int32_t>> order_;  // (interface, place in all_)
  CrackInputs given_;
  std::int32_t local_iface(std::int32_t global) const;
  // The step's inputs of one kind of charge: each owned loaded block's value(local block), and
  // the crack list of gas field g, gathered from every rank; each block's value handed to
  // set(index, value); the whole crack list into given_.
  template <class Value, class Set>
  void gather_inputs(const Model& l, const Loaded& at, const GasField& g, Value value, Set set);
  // The gas field's crack faces' loads on the part, in the whole list's order.
  void crack_loads(Model& l, GasField& g, AppliedLoads::Owned& own) const;
  // Block lb inflated by pressure p (its owner books the loads).
  void inflate(Model& l, std::int32_t lb, double p, AppliedLoads::Owned& own) const;
};

}  // namespace cdem
