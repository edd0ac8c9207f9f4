// The halo stage over MPI (halo_check.hpp): one part per rank, its ghosts' positions and
// velocities received from their owners each step (HaloExchange, parallel/halo.hpp), gets the
// whole model's bits for its own blocks, step after step. Each rank also steps the whole model
// (the reference), and the energy balance and fracture degree summed over the parts must be
// the whole's bits. Run by ctest with mpirun on 2, 3 and 4 ranks (CMakeLists.txt).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>

#include "cdem/analysis/damage.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/solver/run_halo.hpp"
#include "verification/halo_check.hpp"

namespace cdem {
namespace {

using namespace halo_check;

void check_my_part(const HaloCase& hc, std::int64_t steps) {
  const int n = ranks().size, r = ranks().rank;
  ASSERT_GT(n, 1) << "run under mpirun with 2 ranks or more";
  const auto part = parts_of(hc.model, n);
  std::unique_ptr<HaloExchange> halo;
  const Refresh refresh = [&](int, const PartModel& pm, Simulation& sim, const Simulation&) {
    if (!halo) halo = std::make_unique<HaloExchange>(pm, part);
    halo->exchange(sim.model());
  };
  const std::int64_t cut = step_parts(hc, part, n, {r}, steps, refresh);
  ASSERT_TRUE(halo);
  EXPECT_FALSE(halo->peers().empty());
  EXPECT_GT(halo->nodes_received(), 0u);
  // the same whole model on every rank: the cracks between parts are counted alike
  EXPECT_GT(cut, 0) << hc.what;
  EXPECT_EQ(max_over_ranks(cut), cut);
}

TEST(HaloMpi, TetBox) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_my_part(spall_box(mode), 60);
}

TEST(HaloMpi, Plate2D) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_my_part(plate_2d(mode), 120);
}

// A bar across parts (issue 17's test; solver/halo_charges.hpp): a granite box with a bar along its
// axis (tests/verification/cases/bar_box_3d.toml, 0.25 ms, its gas filling cracks), its part per rank
// stepped by the halo stage as `run` does (HaloRun: METIS parts, the bars' state stepped on every
// rank from the gathered inputs), beside the whole model stepped by one process's code on every
// rank. After every step, bitwise: every own node's force, position and velocity, every own
// block's stress (it holds the bar's pressure), every bound block's applied pressure, each deck's
// gas state, the gas's fill and pressure on every interface, and the explosive work. The bar's
// bound blocks lie in more than one part, and the gas fills cracks between parts.
TEST(HaloMpi, BarAcrossParts) {
  const int n = ranks().size, r = ranks().rank;
  ASSERT_GT(n, 1) << "run under mpirun with 2 ranks or more";
  ScopedThreads th(1);
  const Case c = load_case(std::string(CDEM_SOURCE_DIR) + "/tests/verification/cases/bar_box_3d.toml");
  const Mesh mesh = load_mesh(c);
  PreparedCase ref = prepare_case(c, mesh), mine = prepare_case(c, mesh);
  add_charge_loads(ref);
  HaloRun halo(c, mesh, mine.sim, mine.bars, mine.solids, ranks());
  ASSERT_TRUE(halo.charges);
  // the bar's bound blocks in more than one part
  std::vector<int> seen(static_cast<std::size_t>(n), 0);
  for (auto b : ref.bars.elem_block) seen[static_cast<std::size_t>(halo.part[static_cast<std::size_t>(b)])] = 1;
  int parts_of_bar = 0;
  for (int s : seen) parts_of_bar += s;
  EXPECT_GT(parts_of_bar, 1) << "the bar lies in one part: the test does not cross a boundary";
  const Simulation& part = *halo.sim;
  const Model& l = part.model();
  const Model& w = ref.sim.model();
  // local -> global, from the run's cut (the part's blocks are the whole's in order)
  std::vector<std::int32_t> gblock, gnode;
  std::vector<std::uint8_t> own;
  part_blocks(w, halo.part, r, gblock, own);
  for (auto b : gblock)
    for (auto k = w.block_first_node[static_cast<std::size_t>(b)]; k < w.block_first_node[static_cast<std::size_t>(b) + 1]; ++k)
      gnode.push_back(k);
  ASSERT_EQ(gblock.size(), l.n_blocks());
  ASSERT_EQ(gnode.size(), l.n_nodes());
  const GasField& ga = ref.bars.gas;
  const GasField& gb = mine.bars.gas;
  std::int64_t steps = 0, crack_steps = 0;
  while (ref.sim.time() < c.end_time) {
    ref.sim.step(true);  // (sampled: the kinetic energies too)
    halo.step(true);
    ++steps;
    for (std::size_t lb = 0; lb < gblock.size(); ++lb) {
      if (!own[lb]) continue;
      const auto g = static_cast<std::size_t>(gblock[lb]);
      ASSERT_TRUE(halo_check::same(l.stress[lb], w.stress[g])) << "block " << g << ", step " << steps;
      for (auto k = l.block_first_node[lb]; k < l.block_first_node[lb + 1]; ++k) {
        const auto gn = static_cast<std::size_t>(gnode[static_cast<std::size_t>(k)]);
        ASSERT_TRUE(halo_check::same(l.f[static_cast<std::size_t>(k)], w.f[gn]) &&
                    halo_check::same(l.x[static_cast<std::size_t>(k)], w.x[gn]) &&
                    halo_check::same(l.v[static_cast<std::size_t>(k)], w.v[gn]))
            << "node " << gn << " (block " << g << "), step " << steps;
      }
    }
    ASSERT_EQ(std::memcmp(ref.bars.elem_sigma.data(), mine.bars.elem_sigma.data(), ref.bars.elem_sigma.size() * sizeof(double)), 0)
        << "bound blocks' pressure, step " << steps;
    for (std::size_t k = 0; k < ga.bodies.size(); ++k) {
      ASSERT_TRUE(halo_check::same(ga.bodies[k].pressure, gb.bodies[k].pressure) &&
                  halo_check::same(ga.bodies[k].v_cracks, gb.bodies[k].v_cracks) &&
                  halo_check::same(ga.bodies[k].vented, gb.bodies[k].vented) &&
                  halo_check::same(ga.bodies[k].work, gb.bodies[k].work))
          << "deck " << k << ", step " << steps;
      if (ga.bodies[k].v_cracks > 0) ++crack_steps;
    }
    ASSERT_TRUE(ga.iface_fill == gb.iface_fill && ga.iface_body == gb.iface_body && ga.block_body == gb.block_body &&
                ga.iface_gas_p == gb.iface_gas_p)
        << "the gas's fill, step " << steps;
    // the energy balance and the fracture degree: each rank's own terms, summed exactly over the
    // ranks (every rank calls it: a collective), the bits of the whole model's sums
    const EnergyBalance ew = ref.sim.energy(), ep = part.energy();
    ASSERT_EQ(std::memcmp(&ew, &ep, sizeof ew), 0) << "the energy balance, step " << steps;
    const FractureDegree fw = fracture_degree(w), fp = fracture_summary(l, part.own_masks().iface, rank_reducer()).degree;
    ASSERT_TRUE(halo_check::same(fw.area, fp.area) && halo_check::same(fw.tensile, fp.tensile) && fw.broken == fp.broken &&
                fw.total == fp.total)
        << "the fracture degree, step " << steps;
  }
  // the gas filled cracks between parts
  std::int64_t filled = 0, filled_cut = 0;
  for (std::size_t i = 0; i < w.n_ifaces(); ++i) {
    if (!(ga.iface_fill[i] > 0)) continue;
    ++filled;
    filled_cut += halo.part[static_cast<std::size_t>(w.iface_block_a[i])] != halo.part[static_cast<std::size_t>(w.iface_block_b[i])];
  }
  if (ranks().root())
    std::printf("[halo] 3D bar box on %d ranks: the bar's blocks in %d parts, %lld steps (%lld with gas in "
                "cracks), %lld cracks filled (%lld between parts), explosive work %.6g J\n",
                n, parts_of_bar, static_cast<long long>(steps), static_cast<long long>(crack_steps),
                static_cast<long long>(filled), static_cast<long long>(filled_cut), ref.sim.energy().explosive_work);
  EXPECT_GT(crack_steps, 0);
  EXPECT_GT(filled_cut, 0) << "no crack between parts took gas";
}

}  // namespace
}  // namespace cdem

namespace {
cdem::RankSession* g_session = nullptr;
// A failure on one rank ends every rank (MPI_Abort): the others would wait for its messages.
class AbortOnFailure : public ::testing::EmptyTestEventListener {
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (!r.failed()) return;
    std::fprintf(stderr, "rank %d: %s:%d: %s\n", cdem::ranks().rank, r.file_name() ? r.file_name() : "?",
                 r.line_number(), r.summary());
    std::fflush(stderr);
    g_session->finish(1);
  }
};
}  // namespace

int main(int argc, char** argv) {
  cdem::RankSession session(&argc, &argv);
  g_session = &session;
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::UnitTest::GetInstance()->listeners().Append(new AbortOnFailure);
  // (only rank 0 prints gtest's report; every rank's failures set its exit code, which mpirun returns)
  if (!cdem::ranks().root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int rc = RUN_ALL_TESTS();
  return session.finish(rc == 0 ? 0 : 3);
}
