// The halo stage over MPI (halo_check.hpp): one part per rank, its ghosts' positions and
// velocities received from their owners each step (HaloExchange, parallel/halo.hpp), gets the
// whole model's bits for its own blocks, step after step. Each rank also steps the whole model
// (the reference), and the energy balance and fracture degree summed over the parts must be
// the whole's bits. Run by ctest with mpirun on 2, 3 and 4 ranks (CMakeLists.txt).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>

#include "cdem/analysis/damage.hpp"
#include "cdem/parallel/partition.hpp"
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

// A case run by the halo stage as `run` does (HaloRun) beside the whole model stepped by one
// process's code on every rank (the reference), and the part's blocks and nodes as the whole's.
struct HaloBeside {
  Case c;
  Mesh mesh;
  PreparedCase ref, mine;
  HaloRun halo;
  std::vector<std::int32_t> gblock, gnode;  // local -> global
  std::vector<std::uint8_t> own;
  std::int64_t steps = 0;
  explicit HaloBeside(const std::string& path, const std::vector<std::string>& sets = {})
      : c(load_case(path, sets)), mesh(load_mesh(c)), ref(prepare_case(c, mesh)), mine(prepare_case(c, mesh)),
        halo(c, mesh, mine.sim, mine.bars, mine.solids, ranks()) {
    add_charge_loads(ref);
    const Model& w = ref.sim.model();
    // (from the run's cut: the part's blocks are the whole's in order)
    part_blocks(w, halo.part, ranks().rank, gblock, own);
    for (auto b : gblock)
      for (auto k = w.block_first_node[static_cast<std::size_t>(b)]; k < w.block_first_node[static_cast<std::size_t>(b) + 1]; ++k)
        gnode.push_back(k);
  }
  // How many parts hold blocks of the list (a charge's).
  int parts_of(const std::vector<std::int32_t>& blocks) const {
    std::vector<int> seen(static_cast<std::size_t>(ranks().size), 0);
    for (auto b : blocks) seen[static_cast<std::size_t>(halo.part[static_cast<std::size_t>(b)])] = 1;
    int k = 0;
    for (int x : seen) k += x;
    return k;
  }
  // One step of both, then bitwise: every own node's force, position and velocity, every own
  // block's stress (it holds a charge's pressure), the whole energy balance and the fracture
  // degree (each rank's own terms, summed exactly over the ranks: a collective).
  ::testing::AssertionResult step() {
    ref.sim.step(true);  // (sampled: the kinetic energies too)
    halo.step(true);
    ++steps;
    const Simulation& part = *halo.sim;
    const Model& l = part.model();
    const Model& w = ref.sim.model();
    auto fail = ::testing::AssertionFailure();
    if (l.n_blocks() != gblock.size() || l.n_nodes() != gnode.size()) return fail << "the part is not the run's cut";
    for (std::size_t lb = 0; lb < gblock.size(); ++lb) {
      if (!own[lb]) continue;
      const auto g = static_cast<std::size_t>(gblock[lb]);
      if (!halo_check::same(l.stress[lb], w.stress[g])) return fail << "block " << g << "'s stress, step " << steps;
      for (auto k = l.block_first_node[lb]; k < l.block_first_node[lb + 1]; ++k) {
        const auto gn = static_cast<std::size_t>(gnode[static_cast<std::size_t>(k)]);
        const auto ln = static_cast<std::size_t>(k);
        if (!(halo_check::same(l.f[ln], w.f[gn]) && halo_check::same(l.x[ln], w.x[gn]) && halo_check::same(l.v[ln], w.v[gn])))
          return fail << "node " << gn << " (block " << g << "), step " << steps;
      }
    }
    const EnergyBalance ew = ref.sim.energy(), ep = part.energy();
    if (std::memcmp(&ew, &ep, sizeof ew) != 0) return fail << "the energy balance, step " << steps;
    const FractureDegree fw = fracture_degree(w), fp = fracture_summary(l, part.own_masks().iface, rank_reducer()).degree;
    if (!(halo_check::same(fw.area, fp.area) && halo_check::same(fw.tensile, fp.tensile) && fw.broken == fp.broken &&
          fw.total == fp.total))
      return fail << "the fracture degree, step " << steps;
    return ::testing::AssertionSuccess();
  }
  // The gas of a kind of charge: each deck's state and every interface's fill, body and pressure.
  ::testing::AssertionResult same_gas(const GasField& ga, const GasField& gb) const {
    for (std::size_t k = 0; k < ga.bodies.size(); ++k)
      if (!(halo_check::same(ga.bodies[k].pressure, gb.bodies[k].pressure) &&
            halo_check::same(ga.bodies[k].v_cracks, gb.bodies[k].v_cracks) &&
            halo_check::same(ga.bodies[k].vented, gb.bodies[k].vented) && halo_check::same(ga.bodies[k].work, gb.bodies[k].work)))
        return ::testing::AssertionFailure() << "deck " << k << "'s gas, step " << steps;
    if (!(ga.iface_fill == gb.iface_fill && ga.iface_body == gb.iface_body && ga.block_body == gb.block_body &&
          ga.iface_gas_p == gb.iface_gas_p))
      return ::testing::AssertionFailure() << "the gas's fill, step " << steps;
    return ::testing::AssertionSuccess();
  }
  // Interfaces between parts whose gas fill is positive.
  std::int64_t filled_between_parts(const GasField& g, std::int64_t& filled) const {
    const Model& w = ref.sim.model();
    std::int64_t cut = 0;
    filled = 0;
    for (std::size_t i = 0; i < w.n_ifaces(); ++i) {
      if (!(g.iface_fill[i] > 0)) continue;
      ++filled;
      cut += halo.part[static_cast<std::size_t>(w.iface_block_a[i])] != halo.part[static_cast<std::size_t>(w.iface_block_b[i])];
    }
    return cut;
  }
};

// A bar across parts (issue 17's test; solver/halo_charges.hpp): a granite box with a bar along its
// axis (tests/verification/cases/bar_box_3d.toml, 0.25 ms, its gas filling cracks), its part per rank
// stepped by the halo stage as `run` does (HaloRun: METIS parts, the bars' state stepped on every
// rank from the gathered inputs), beside the whole model stepped by one process's code on every
// rank. After every step, bitwise: every own node's force, position and velocity, every own
// block's stress (it holds the bar's pressure), every bound block's applied pressure, each deck's
// gas state, the gas's fill and pressure on every interface, and the explosive work. The bar's
// bound blocks lie in more than one part, and the gas fills cracks between parts.
TEST(HaloMpi, BarAcrossParts) {
  const int n = ranks().size;
  ASSERT_GT(n, 1) << "run under mpirun with 2 ranks or more";
  ScopedThreads th(1);
  HaloBeside hb(std::string(CDEM_SOURCE_DIR) + "/tests/verification/cases/bar_box_3d.toml");
  ASSERT_TRUE(hb.halo.charges);
  const int parts_of_bar = hb.parts_of(hb.ref.bars.elem_block);
  EXPECT_GT(parts_of_bar, 1) << "the bar lies in one part: the test does not cross a boundary";
  std::int64_t crack_steps = 0;
  while (hb.ref.sim.time() < hb.c.end_time) {
    ASSERT_TRUE(hb.step());
    ASSERT_EQ(std::memcmp(hb.ref.bars.elem_sigma.data(), hb.mine.bars.elem_sigma.data(),
                          hb.ref.bars.elem_sigma.size() * sizeof(double)), 0)
        << "bound blocks' pressure, step " << hb.steps;
    ASSERT_TRUE(hb.same_gas(hb.ref.bars.gas, hb.mine.bars.gas));
    for (const auto& body : hb.ref.bars.gas.bodies) crack_steps += body.v_cracks > 0;
  }
  std::int64_t filled = 0;
  const std::int64_t filled_cut = hb.filled_between_parts(hb.ref.bars.gas, filled);
  if (ranks().root())
    std::printf("[halo] 3D bar box on %d ranks: the bar's blocks in %d parts, %lld steps (%lld with gas in "
                "cracks), %lld cracks filled (%lld between parts), explosive work %.6g J\n",
                n, parts_of_bar, static_cast<long long>(hb.steps), static_cast<long long>(crack_steps),
                static_cast<long long>(filled), static_cast<long long>(filled_cut), hb.ref.sim.energy().explosive_work);
  EXPECT_GT(crack_steps, 0);
  EXPECT_GT(filled_cut, 0) << "no crack between parts took gas";
}

// Solid charges across parts (solver/halo_charges.hpp), stepped as the bar box above. After every
// step, bitwise besides the above: each explosive block's volume ratio, burnt fraction, pressure
// and collapse, and the gas. Two cases:
// - a granite box with a solid charge along its axis (tests/verification/cases/solid_box_3d.toml,
//   80 us: 1 431 explosive tetrahedra, their gas filling cracks, 3 of them collapsing). On 3 and 4
//   ranks its blocks and the gas's cracks lie in 2 parts; on 2, METIS keeps the charge, in the
//   mesh's fine zone, whole in one part.
// - SPEC 5.1's solid case without contact, to 0.6 ms: an explosive block collapses at 0.55 ms,
//   which on 2 and 4 ranks another part holds as a ghost (it shares a vertex with one of that
//   part's blocks), and which that part lets go of too (its ties at that vertex split).
// (returns whether the charge or its gas crossed a part boundary: the charge in more than one
// part and a crack between parts filled)
struct Crossed {
  bool charge = false, gas = false;
};
void solid_across_parts(const std::string& path, const std::vector<std::string>& sets, Crossed& crossed) {
  const int n = ranks().size;
  ASSERT_GT(n, 1) << "run under mpirun with 2 ranks or more";
  ScopedThreads th(1);
  HaloBeside hb(path, sets);
  ASSERT_TRUE(hb.halo.charges);
  const SolidCharges &sa = hb.ref.solids, &sb = hb.mine.solids;
  auto same = [](const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
  };
  while (hb.ref.sim.time() < hb.c.end_time) {
    ASSERT_TRUE(hb.step());
    ASSERT_TRUE(same(sa.v, sb.v) && same(sa.lambda, sb.lambda) && same(sa.p, sb.p) && sa.dead == sb.dead &&
                sa.dead_count == sb.dead_count)
        << "the explosive blocks' state, step " << hb.steps;
    ASSERT_TRUE(hb.same_gas(sa.gas, sb.gas));
  }
  // the collapsed blocks another part holds as ghosts (a mesh vertex shared with one of its
  // blocks): that part lets go of them too
  const Model& w = hb.ref.sim.model();
  std::vector<std::int32_t> vstart, vlist;
  vertex_blocks(w.block_first_node, w.node_vertex, vstart, vlist);
  std::int64_t ghosts = 0;
  for (std::size_t i = 0; i < sa.block.size(); ++i) {
    if (!sa.dead[i]) continue;
    const std::int32_t b = sa.block[i];
    const std::int32_t pb = hb.halo.part[static_cast<std::size_t>(b)];
    bool ghost = false;
    for (auto k = w.block_first_node[b]; k < w.block_first_node[b + 1]; ++k) {
      const auto v = static_cast<std::size_t>(w.node_vertex[static_cast<std::size_t>(k)]);
      for (auto j = vstart[v]; j < vstart[v + 1]; ++j) ghost = ghost || hb.halo.part[static_cast<std::size_t>(vlist[j])] != pb;
    }
    ghosts += ghost;
  }
  std::int64_t filled = 0;
  const std::int64_t filled_cut = hb.filled_between_parts(sa.gas, filled);
  const int parts_of_charge = hb.parts_of(sa.block);
  if (ranks().root())
    std::printf("[halo] %s on %d ranks: the charge's %zu blocks in %d parts, %lld steps, %lld collapsed (%lld of "
                "them ghosts of another part), %lld cracks filled (%lld between parts), explosive work %.6g J\n",
                hb.c.title.c_str(), n, sa.block.size(), parts_of_charge, static_cast<long long>(hb.steps),
                static_cast<long long>(sa.dead_count), static_cast<long long>(ghosts), static_cast<long long>(filled),
                static_cast<long long>(filled_cut), hb.ref.sim.energy().explosive_work);
  EXPECT_GT(sa.dead_count, 0) << "no explosive block collapsed";
  EXPECT_GT(filled, 0) << "the gas filled no crack";
  crossed.charge = crossed.charge || parts_of_charge > 1;
  crossed.gas = crossed.gas || filled_cut > 0;
}

TEST(HaloMpi, SolidAcrossParts) {
  Crossed crossed;
  solid_across_parts(std::string(CDEM_SOURCE_DIR) + "/tests/verification/cases/solid_box_3d.toml", {}, crossed);
  solid_across_parts(std::string(CDEM_SOURCE_DIR) + "/examples/single_hole_2d/solid.toml",
                     {"contact.enabled=false", "simulation.end_time=6e-4"}, crossed);
  // on every rank count, one of the two crosses the parts
  EXPECT_TRUE(crossed.charge) << "both charges lie in one part: the test does not cross a boundary";
  EXPECT_TRUE(crossed.gas) << "no crack between parts took gas";
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
