// The halo stage's check (parallel/halo.hpp), shared by the one-process test
// (verification/test_halo.cpp: every part in one process, the ghosts refreshed from a whole-model
// run) and the distributed one (mpi/test_halo_mpi.cpp: a part per rank, the ghosts received from
// their owners over MPI): a part's own blocks stepped in its local model get the whole model's
// bits, step after step. Bitwise (memcmp): the claim is identity, so no tolerance.
//
// The models: the 3D tet box of test_determinism.cpp, spalled by a pressure pulse on its top face
// (fracture-energy interfaces, a non-reflecting side, a roller side), and the shipped 2D plate
// with a pressurised hole on a coarser unstructured (Gmsh) mesh (Mohr-Coulomb interfaces,
// non-reflecting sides), in both interface modes. The parts: METIS k-way (or, without METIS,
// ranges of the block order).
#pragma once
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cdem/io/case.hpp"
#include "cdem/parallel/halo.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/model_builders.hpp"

namespace cdem::halo_check {

using namespace test_models;

template <class T>
bool same(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

struct HaloCase {
  Model model;
  Case c;
  std::string what;
};

inline HaloCase spall_box(InterfaceMode mode) {
  auto mat = rock(30e9, 0.25, 2600);
  auto im = interface_of(InterfaceLaw::FractureEnergy, 5e6, 15e6, 35);
  im.gt = 50;
  im.gs = 500;
  im.dilation_deg = 10;
  HaloCase s{make_model(tet_box(6, 6, 6, 0.6, 0.6, 0.6), mat, im), make_case({mat}, {im}), "tet box 6x6x6"};
  s.c.interface_mode = mode;
  BoundaryCondition p;
  p.faces = "top";
  p.type = BoundaryType::Pressure;
  p.value = 100e6;
  p.table.points = {{0.0, 0.0}, {2e-5, 1.0}, {4e-5, 0.0}};
  s.c.boundaries.push_back(p);
  BoundaryCondition nr;
  nr.faces = "left";
  nr.type = BoundaryType::NonReflecting;
  s.c.boundaries.push_back(nr);
  BoundaryCondition fx;
  fx.faces = "front";
  fx.type = BoundaryType::Roller;
  s.c.boundaries.push_back(fx);
  return s;
}

inline HaloCase plate_2d(InterfaceMode mode) {
  const std::string path = std::string(CDEM_SOURCE_DIR) + "/examples/plate_with_hole_2d/case.toml";
  Case c = load_case(path, {"mesh.generate.element_size=0.1", "mesh.generate.refine.0.size=0.04"});
  c.interface_mode = mode;
  const Mesh mesh = load_mesh(c);
  return HaloCase{build_case_model(c, mesh), c, "plate_with_hole_2d (coarse)"};
}

inline std::vector<std::int32_t> parts_of(const Model& model, int nparts) {
  const BlockGraph graph = block_graph(model);
  return have_metis() ? partition_kway(graph, nparts) : ranges_to_parts(block_ranges(graph, nparts));
}

// The ghosts of part p's local model (`pm`, stepped by `sim`) made the whole model's before a step.
using Refresh = std::function<void(int p, const PartModel& pm, Simulation& sim, const Simulation& whole)>;

// Steps the whole model and the parts `mine` of `part` side by side for `steps` steps, comparing
// after each step every own node's position and velocity, every own block's stress, and every
// spring point of an interface with an own block (forces, state, opening, dissipation, tie).
// Returns the spring points broken on interfaces between two parts at the end.
inline std::int64_t step_parts(const HaloCase& hc, const std::vector<std::int32_t>& part, int nparts,
                               const std::vector<int>& mine, std::int64_t steps, const Refresh& refresh) {
  const Model& model = hc.model;
  ScopedThreads th(1);
  Simulation whole(model, hc.c);
  // A part's set-up: the whole model's time step and omega^2 bound (a distributed run's
  // reductions over the ranks).
  Case part_case = hc.c;
  part_case.fixed_dt = whole.dt();
  std::vector<PartModel> parts;
  std::vector<std::unique_ptr<Simulation>> sims;
  std::size_t ghosts = 0;
  for (int p : mine) {
    parts.push_back(cut_part(model, part, p));
    WholeModelSetup ws{whole.omega2_max(), {}, {}, !whole.model().local_damping.empty(), &whole.stable()};
    if (hc.c.interface_mode == InterfaceMode::Tied) ws.node_springs = node_spring_counts(model, parts.back());
    sims.push_back(std::make_unique<Simulation>(parts.back().model, part_case, &ws));
    ghosts += parts.back().ghost_blocks;
  }
  for (std::size_t k = 0; k < mine.size(); ++k) refresh(mine[k], parts[k], *sims[k], whole);
  const int np = model.springs_per_iface;
  std::int64_t compared_points = 0;
  for (std::int64_t k = 0; k < steps; ++k) {
    whole.step();
    const Model& w = whole.model();
    for (std::size_t j = 0; j < mine.size(); ++j) {
      const int p = mine[j];
      sims[j]->step();
      const Model& l = sims[j]->model();
      const PartModel& pm = parts[j];
      for (std::size_t lb = 0; lb < pm.block.size(); ++lb) {
        if (!pm.own[lb]) continue;
        const auto gb = static_cast<std::size_t>(pm.block[lb]);
        EXPECT_TRUE(same(l.stress[lb], w.stress[gb])) << "part " << p << ", block " << gb << ", step " << k + 1;
        for (auto n = l.block_first_node[lb]; n < l.block_first_node[lb + 1]; ++n) {
          const auto gn = static_cast<std::size_t>(pm.node[static_cast<std::size_t>(n)]);
          if (!same(l.x[n], w.x[gn]) || !same(l.v[n], w.v[gn])) {
            ADD_FAILURE() << "part " << p << ", node " << gn << " (block " << gb << "), step " << k + 1;
            return -1;
          }
        }
      }
      for (std::size_t li = 0; li < pm.iface.size(); ++li) {
        if (!pm.own[static_cast<std::size_t>(l.iface_block_a[li])] && !pm.own[static_cast<std::size_t>(l.iface_block_b[li])]) continue;
        const auto gi = static_cast<std::size_t>(pm.iface[li]);
        for (int q = 0; q < np; ++q) {
          const std::size_t ls = li * np + q, gs = gi * np + q;
          if (!(same(l.sp_fn[ls], w.sp_fn[gs]) && same(l.sp_fs[ls], w.sp_fs[gs]) &&
                l.sp_state[ls] == w.sp_state[gs] && (w.sp_w.empty() || same(l.sp_w[ls], w.sp_w[gs])) &&
                same(l.sp_dissipated[ls], w.sp_dissipated[gs]) && (!w.tied || l.sp_tied[ls] == w.sp_tied[gs]))) {
            ADD_FAILURE() << "part " << p << ", interface " << gi << " point " << q << ", step " << k + 1;
            return -1;
          }
          ++compared_points;
        }
      }
    }
    for (std::size_t j = 0; j < mine.size(); ++j) refresh(mine[j], parts[j], *sims[j], whole);
  }
  // The run must crack across the cuts, or the ghost zone's break paths are not exercised.
  const Model& w = whole.model();
  std::int64_t broken = 0, broken_cut = 0;
  for (std::size_t s = 0; s < w.n_springs(); ++s) {
    const bool b = w.sp_state[s] != kIntact || (w.tied && !w.sp_tied[s]);
    const auto i = s / static_cast<std::size_t>(np);
    broken += b;
    broken_cut += b && part[static_cast<std::size_t>(w.iface_block_a[i])] != part[static_cast<std::size_t>(w.iface_block_b[i])];
  }
  std::printf("[halo] %s [%s], %d parts (%s), %zu of them here: %zu blocks, %zu ghost blocks here, %lld steps, "
              "%lld points broken (%lld between parts), %lld point-steps compared\n",
              hc.what.c_str(), name_of(hc.c.interface_mode), nparts, have_metis() ? "METIS" : "ranges", mine.size(),
              model.n_blocks(), ghosts, static_cast<long long>(steps), static_cast<long long>(broken),
              static_cast<long long>(broken_cut), static_cast<long long>(compared_points));
  return broken_cut;
}

// Every part in this process, the ghosts copied from the whole model.
inline void copy_ghosts(int, const PartModel& pm, Simulation& sim, const Simulation& whole) {
  Model& l = sim.model();
  const Model& w = whole.model();
  for (auto ln : pm.ghost_nodes) {
    const auto g = static_cast<std::size_t>(pm.node[static_cast<std::size_t>(ln)]);
    l.x[static_cast<std::size_t>(ln)] = w.x[g];
    l.v[static_cast<std::size_t>(ln)] = w.v[g];
  }
}

}  // namespace cdem::halo_check
