// The halo stage's side of a run (parallel/halo.hpp, docs/parallel.md; run_halo.cpp).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "cdem/analysis/uplift.hpp"
#include "cdem/io/case.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/parallel/halo.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/solver/halo_charges.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

// The halo stage's parts of a model (set up), one per rank, from its block graph g (block_graph
// without charge groups): METIS k-way (ranges of the block order without METIS). A charge's blocks are not kept together: the
// charges' state is stepped on every rank (halo_charges.hpp), so nothing depends on it, and the
// tests need charges across parts. `check --parts` prints this partition.
std::vector<std::int32_t> halo_parts(const BlockGraph& g, int parts);

// This rank's part of the model with its ghost zone, set up from the same case with the whole
// model's time step, damping and frequency bound (`whole`); the exchange of its ghosts' motion;
// its nodes' uplift maxima.
struct HaloRun {
  std::unique_ptr<Simulation> sim;
  std::unique_ptr<HaloExchange> exchange;
  std::unique_ptr<HaloCharges> charges;  // the charges' state, stepped on every rank (halo_charges.hpp)
  UpliftTracker uplift{Model{}, Vec3{0, 0, 1}, 0};
  std::vector<std::int32_t> part;  // the rank stepping each block of the whole model
  PartitionQuality quality;
  std::size_t own_blocks = 0, ghost_blocks = 0;

  // METIS parts of `whole` (ranges of the block order without METIS), one per rank; this rank's
  // cut from the case's model and set up. `bars`, `solids`: the whole model's charges, whose state
  // every rank steps (kept by the caller).
  HaloRun(const Case& c, const Mesh& mesh, const Simulation& whole, BarCharges& bars, SolidCharges& solids,
          const RankInfo& rk);
  // One step of the part, then its ghosts' motion from their owners.
  void step(bool sample);
};

}  // namespace cdem
