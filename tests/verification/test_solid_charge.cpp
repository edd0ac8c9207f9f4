// Verification of the solid explosion model (SPEC 3; explosive/charges.hpp) and of the energy
// book-keeping of the explosive loads (SPEC 4), on small 2D models built in code:
//  - burn front: every explosive block ignites at t_D0 + |centroid - initiation point| / D
//    (exact), and in a run its pressure becomes non-zero first in the step after that time;
//  - pressure = lambda EOS(v) with v from the block's current volume, at every step of a run
//    and for a block stretched by hand (closed-form Landau first stage);
//  - a collapsed (inverted) explosive block is reported (dead flag, dead_count), carries no
//    pressure from then on, and the run stays finite;
//  - energy: in a bar-loaded run with unbreakable elastic interfaces, the explosive work
//    W = sum F(n) . (v(n-1/2) + v(n+1/2)) / 2 dt equals the mechanical energy gained (no
//    dissipation) to within 1 %, and likewise for a solid-charge run.
// Numbers: docs/verification_charges.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/eos.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/charge_builders.hpp"

namespace cdem {
namespace {

using namespace test_charges;

constexpr double kD = 5000.0;                              // emulsion detonation velocity, m/s
constexpr double kP0 = 1150.0 * 5000.0 * 5000.0 / 8.0;     // rho D^2 / (2 (gamma1 + 1)), Pa

// A stiff rock (E 60 GPa, rho 2700 kg/m^3) so that the full emulsion pressure (3.6 GPa) moves
// the 5 cm blocks by well under their size within the 0.1 ms these tests simulate.
BlockMaterial stiff_rock() { return rock(60e9, 0.25, 2700, "rock"); }

BlockMaterial emulsion_material() {
  BlockMaterial ex;
  ex.name = "emulsion_charge";
  ex.regions = {"charge"};
  ex.explosive = "emulsion";
  ex.density = 1150;  // what load_case fills in from the explosive
  ex.youngs = 1e9;    // load_case's defaults for an explosive region (unused: no shear stiffness)
  ex.poisson = 0.25;
  return ex;
}

// 1 m x 1 m of 5 cm quads; the charge is the column x in [0.45, 0.50], y in [0.5, 0.8]
// (6 explosive blocks), a hole of diameter 0.05 m from (0.475, 0.8) down to (0.475, 0.5).
struct SolidSetup {
  Model model;
  Case c;
};
SolidSetup solid_setup(double delay, bool initiate_top) {
  Mesh mesh = quad_grid(20, 20, 1.0, 1.0);
  assign_region(mesh, "charge", [](Vec3 p) { return p.x > 0.45 && p.x < 0.5 && p.y > 0.5 && p.y < 0.8; });
  const std::vector<BlockMaterial> mats{stiff_rock(), emulsion_material()};
  const std::vector<InterfaceMaterial> ifs{interface_of(InterfaceLaw::Elastic)};
  SolidSetup s{build_model(mesh, mats, ifs, "solid test model"),
               charge_case(mats, ifs,
                           {make_hole("solid_hole", {0.475, 0.8, 0}, {0.475, 0.5, 0}, 0.05,
                                      {{0.3, delay, initiate_top, 0.0}}, ChargeModel::Solid)})};
  return s;
}

// Ignition times are t_D0 + distance / D exactly: centroids at y = 0.525 + 0.05 k, initiation
// at y = 0.5 (bottom) or 0.8 (top). Burn time L_c / D = 0.05 / D.
TEST(SolidCharge, IgnitionTimesFromCentroidDistance) {
  for (bool top : {false, true}) {
    const auto s = solid_setup(1e-5, top);
    const SolidCharges sc = build_solid_charges(s.model, s.c);
    ASSERT_EQ(sc.block.size(), 6u);
    for (std::size_t i = 0; i < sc.block.size(); ++i) {
      const Vec3 cen = centroid0(s.model, sc.block[i]);
      const double dist = top ? 0.8 - cen.y : cen.y - 0.5;
      // distances are 0.025 + 0.05 k by construction; t ~ 1e-4 s: 1e-18 s is a few ulps.
      const int k = static_cast<int>(std::lround((dist - 0.025) / 0.05));
      EXPECT_NEAR(dist, 0.025 + 0.05 * k, 1e-12);
      EXPECT_NEAR(sc.t_ign[i], 1e-5 + dist / kD, 1e-18) << "block at y = " << cen.y;
      EXPECT_NEAR(sc.burn_time[i], 0.05 / kD, 1e-18);
    }
  }
}

// The run: every step, each explosive block's pressure is lambda EOS(v) with v = current volume
// / initial volume (computed here from the node positions) and lambda = clamp((t - t_ign) / burn,
// 0, 1); the first step with pressure is the first step whose time t_n exceeds t_ign, so
// 0 < t_first - t_ign <= dt.
TEST(SolidCharge, BurnFrontArrivalAndPressureInRun) {
  auto s = solid_setup(1e-5, false);
  Simulation sim(std::move(s.model), s.c);
  SolidCharges sc = build_solid_charges(sim.model(), s.c);
  sim.add_load([&sc](Model& m, AppliedLoads& out, double t) { solid_loads(m, sc, out, t); });
  sim.limit_dt(sc.dt_limit, "explosive blocks");
  const double dt = sim.dt();
  ASSERT_GT(dt, 0.0);
  const double t_last = *std::max_element(sc.t_ign.begin(), sc.t_ign.end());
  const std::size_t nb = sc.block.size();
  std::vector<double> t_first(nb, -1.0);
  double worst_p = 0, worst_v = 0, v_max = 0;
  int steps = 0;
  while (sim.time() < t_last + 0.05 / kD + 20 * dt) {
    sim.step();
    ++steps;
    const double tn = sim.time() - dt;  // the time the loads were evaluated at
    const Model& m = sim.model();
    for (std::size_t i = 0; i < nb; ++i) {
      const auto b = sc.block[i];
      const double v = current_measure(m, b) / m.block_volume0[b];
      const double lam = std::clamp((tn - sc.t_ign[i]) / sc.burn_time[i], 0.0, 1.0);
      const double p = lam > 0 ? lam * eos_pressure(sc.eos[0], v) : 0.0;
      worst_v = std::max(worst_v, std::abs(sc.v[i] - v));
      worst_p = std::max(worst_p, std::abs(sc.p[i] - p) / kP0);
      EXPECT_NEAR(sc.lambda[i], lam, 1e-12);
      EXPECT_NEAR(m.stress[b][0], -sc.p[i], 1e-12 * kP0);
      v_max = std::max(v_max, v);
      if (sc.p[i] > 0 && t_first[i] < 0) t_first[i] = tn;
    }
    for (const auto& x : m.x) ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y)) << "step " << steps;
  }
  // Same formula evaluated on the same doubles: agreement to round-off (1e-12 of P0, of v ~ 1).
  EXPECT_LT(worst_v, 1e-12);
  EXPECT_LT(worst_p, 1e-12);
  EXPECT_GT(v_max, 1.001) << "the charge did not expand: nothing was tested";
  EXPECT_EQ(sc.dead_count, 0);
  EXPECT_EQ(sim.inverted_blocks(), 0);
  double lag_min = 1e300, lag_max = -1e300;
  for (std::size_t i = 0; i < nb; ++i) {
    ASSERT_GE(t_first[i], 0.0) << "block " << i << " never carried pressure";
    const double lag = t_first[i] - sc.t_ign[i];
    lag_min = std::min(lag_min, lag / dt);
    lag_max = std::max(lag_max, lag / dt);
    EXPECT_GT(lag, 0.0) << "block " << i;
    EXPECT_LE(lag, dt * (1 + 1e-9)) << "block " << i;  // within one step (t_n round-off margin)
  }
  std::printf("[ solid    ] burn front: %d steps of dt = %.4g s, first-pressure lag / dt in [%.3f, %.3f], "
              "max v = %.5f\n",
              steps, dt, lag_min, lag_max, v_max);
}

// lambda EOS(v) against the closed-form first Landau stage P0 v^-3 (v below vc ~ 2.3): one
// explosive block stretched by 1.1 in x and y about its centroid (v = 1.21), the others at v = 1,
// long after the burn (lambda = 1). The forces on the stretched block inflate it with p.
TEST(SolidCharge, PressureFromCurrentBlockVolume) {
  auto s = solid_setup(0.0, false);
  Model& m = s.model;
  SolidCharges sc = build_solid_charges(m, s.c);
  const auto b = sc.block[2];
  const Vec3 cen = centroid0(m, b);
  for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) m.x[n] = cen + 1.1 * (m.X[n] - cen);
  AppliedLoads out;
  solid_loads(m, sc, out, 1.0);
  for (std::size_t i = 0; i < sc.block.size(); ++i) {
    const double v = i == 2 ? 1.21 : 1.0;
    EXPECT_NEAR(sc.v[i], v, 1e-12);
    EXPECT_NEAR(sc.lambda[i], 1.0, 0.0);
    EXPECT_NEAR(sc.p[i], kP0 * std::pow(v, -3.0), 1e-12 * kP0) << "block " << i;
  }
  // Nodes of the stretched block: p (s/2) (n1 + n2), magnitude p s / sqrt(2) with s = 1.1 x 0.05.
  int n_checked = 0;
  for (std::size_t k = 0; k < out.node.size(); ++k) {
    if (m.node_block[out.node[k]] != b) continue;
    ++n_checked;
    EXPECT_NEAR(norm(out.force[k]), sc.p[2] * 0.055 / std::sqrt(2.0), 1e-12 * sc.p[2]);
    EXPECT_NEAR(dot(normalized(out.force[k]), normalized(m.x[out.node[k]] - cen)), 1.0, 1e-12);
  }
  EXPECT_EQ(n_checked, 4);
}

// An explosive block collapsed by hand (its node 0 moved beyond node 2, so the quad's signed
// area is negative) during a run: the next solid_loads reports it once (dead flag, dead_count
// = 1), it carries zero pressure (and zero stress) from then on even if it reopens, the other
// blocks keep their pressure, and the following steps stay finite.
TEST(SolidCharge, CollapsedBlockIsReportedAndRunContinues) {
  auto s = solid_setup(0.0, false);
  Simulation sim(std::move(s.model), s.c);
  SolidCharges sc = build_solid_charges(sim.model(), s.c);
  sim.add_load([&sc](Model& m, AppliedLoads& out, double t) { solid_loads(m, sc, out, t); });
  sim.limit_dt(sc.dt_limit, "explosive blocks");
  // Run until block 0 (the first to ignite) is fully burnt and loaded.
  while (sim.time() < sc.t_ign[0] + sc.burn_time[0] + 2 * sim.dt()) sim.step();
  ASSERT_GT(sc.p[0], 0.0);
  ASSERT_EQ(sc.dead_count, 0);
  Model& m = sim.model();
  const auto b = sc.block[0];
  const auto n0 = m.block_first_node[b];
  const Vec3 saved = m.x[n0];
  m.x[n0] = m.x[n0 + 2] + 0.2 * (m.x[n0 + 2] - m.x[n0]);
  ASSERT_LT(current_measure(m, b), 0.0);
  sim.step();
  EXPECT_EQ(sc.dead[0], 1);
  EXPECT_EQ(sc.dead_count, 1);
  EXPECT_LT(sc.v[0], 0.0);
  EXPECT_EQ(sc.p[0], 0.0);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(m.stress[b][k], 0.0);
  // Reopen it: still dead, still no pressure, reported only once.
  m.x[n0] = saved;
  for (int k = 0; k < 200; ++k) {
    sim.step();
    ASSERT_EQ(sc.p[0], 0.0) << "step " << k;
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      ASSERT_TRUE(std::isfinite(m.x[n].x) && std::isfinite(m.x[n].y) && std::isfinite(m.v[n].x) &&
                  std::isfinite(m.v[n].y))
          << "node " << n << " at step " << k;
  }
  EXPECT_EQ(sc.dead_count, 1);
  EXPECT_GT(sc.v[0], 0.5);
  for (std::size_t i = 1; i < sc.block.size(); ++i) EXPECT_GT(sc.p[i], 0.0) << "block " << i;
}

// ---------------------------------------------------------------------------------------------
// Energy balance of the explosive loads
// ---------------------------------------------------------------------------------------------

struct EnergyRun {
  double max_error = 0, w_explosive = 0, mechanical = 0, dissipated = 0;
  int steps = 0;
};

// Runs `sim` for `steps` steps sampling the energy every step; the balance error is taken once
// the explosive work exceeds 1 % of its final value (before that, both sides are ~0).
EnergyRun run_energy(Simulation& sim, int steps, double w_final_estimate) {
  EnergyRun r;
  for (int k = 0; k < steps; ++k) {
    sim.step(true);
    const EnergyBalance e = sim.energy();
    if (e.explosive_work > 0.01 * w_final_estimate) r.max_error = std::max(r.max_error, e.error);
    r.w_explosive = e.explosive_work;
    r.mechanical = e.mechanical();
    r.dissipated = e.damping + e.fracture;
    EXPECT_TRUE(std::isfinite(e.balance)) << "step " << k;
  }
  r.steps = steps;
  return r;
}

// A bar (emulsion, r0 = 5 mm, attenuation (r0 / L_c)^1.25 = 0.056) along the middle of a column
// of 5 cm quads in a free 1 m x 1 m plate, unbreakable elastic interfaces, no damping: the
// explosive work equals the mechanical energy gained (kinetic + block strain + spring strain),
// to within 1 % at every sampled step (the balance error of Simulation::energy()).
TEST(ExplosiveEnergy, BarLoadedRunBalances) {
  const Mesh mesh = quad_grid(20, 20, 1.0, 1.0);
  const std::vector<BlockMaterial> mats{rock()};
  const std::vector<InterfaceMaterial> ifs{interface_of(InterfaceLaw::Elastic)};
  Case c = charge_case(mats, ifs, {bar("energy", {0.475, 0.325, 0}, {0.475, 0.675, 0}, 0.01)});
  Simulation sim(build_model(mesh, mats, ifs, "energy test"), c);
  BarCharges bc = build_bar_charges(sim.model(), c);
  sim.add_load([&bc](Model& m, AppliedLoads& out, double t) { bar_loads(m, bc, out, t); });
  const int steps = static_cast<int>(std::ceil(2e-4 / sim.dt()));
  // A first pass to know the final work, then the checked run (same deterministic result).
  double w_final = 0;
  {
    Simulation probe(build_model(mesh, mats, ifs, "energy test"), c);
    BarCharges bc2 = build_bar_charges(probe.model(), c);
    probe.add_load([&bc2](Model& m, AppliedLoads& out, double t) { bar_loads(m, bc2, out, t); });
    for (int k = 0; k < steps; ++k) probe.step();
    w_final = probe.energy().explosive_work;
  }
  ASSERT_GT(w_final, 0.0);
  const EnergyRun r = run_energy(sim, steps, w_final);
  EXPECT_NEAR(r.w_explosive, w_final, 1e-12 * w_final);  // deterministic
  EXPECT_EQ(r.dissipated, 0.0);                           // elastic interfaces, no damping
  // 1 %: the bound the brief sets; the central-difference balance is O(dt^2) (see the doc).
  EXPECT_LT(r.max_error, 0.01);
  EXPECT_NEAR(r.mechanical, r.w_explosive, 0.01 * r.w_explosive);
  // No net force on the body: the momentum stays ~0 (relative to sum m |v|).
  Vec3 mom{};
  double scale = 0;
  for (std::size_t n = 0; n < sim.model().n_nodes(); ++n) {
    mom += sim.model().mass[n] * sim.model().v[n];
    scale += sim.model().mass[n] * norm(sim.model().v[n]);
  }
  EXPECT_LT(norm(mom), 1e-9 * scale);
  std::printf("[ energy   ] bar: %d steps of dt = %.4g s, W_explosive = %.6g J, mechanical = %.6g J, "
              "max balance error %.3e\n",
              r.steps, sim.dt(), r.w_explosive, r.mechanical, r.max_error);
}

// The same bookkeeping for the solid model (explosive blocks carry pressure only: their work
// goes into the rock and into the kinetic energy of the explosive blocks' nodes).
TEST(ExplosiveEnergy, SolidChargeRunBalances) {
  auto s = solid_setup(0.0, false);
  const Case c = s.c;
  Simulation sim(std::move(s.model), c);
  SolidCharges sc = build_solid_charges(sim.model(), c);
  sim.add_load([&sc](Model& m, AppliedLoads& out, double t) { solid_loads(m, sc, out, t); });
  sim.limit_dt(sc.dt_limit, "explosive blocks");
  const int steps = static_cast<int>(std::ceil(8e-5 / sim.dt()));
  double w_final = 0;
  {
    auto s2 = solid_setup(0.0, false);
    Simulation probe(std::move(s2.model), c);
    SolidCharges sc2 = build_solid_charges(probe.model(), c);
    probe.add_load([&sc2](Model& m, AppliedLoads& out, double t) { solid_loads(m, sc2, out, t); });
    probe.limit_dt(sc2.dt_limit, "explosive blocks");
    for (int k = 0; k < steps; ++k) probe.step();
    w_final = probe.energy().explosive_work;
  }
  ASSERT_GT(w_final, 0.0);
  const EnergyRun r = run_energy(sim, steps, w_final);
  EXPECT_EQ(r.dissipated, 0.0);
  EXPECT_EQ(sc.dead_count, 0);
  EXPECT_LT(r.max_error, 0.01);
  std::printf("[ energy   ] solid: %d steps of dt = %.4g s, W_explosive = %.6g J, mechanical = %.6g J, "
              "max balance error %.3e\n",
              r.steps, sim.dt(), r.w_explosive, r.mechanical, r.max_error);
}

}  // namespace
}  // namespace cdem
