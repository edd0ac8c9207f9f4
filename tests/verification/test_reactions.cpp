// Reaction forces of the velocity constraints (ReactionMeter, reactions.csv) and gravity on a
// heavy model (issue 14).
//  - A static bar: bottom fixed, a pressure p on the top. Pre-stressed to sigma_zz = -p it is in
//    equilibrium from the first step; loaded from rest it settles under local damping. Either
//    way the bottom's reaction is the applied load p A (1e-6, the issue's criterion), and the
//    meter's recomputed constrained velocities are the kernel's.
//  - A heavy block at rest under gravity on a fixed base (a 13.6 t granite cylinder, the
//    issue's model): the run does not stop as unstable, its energy error stays <= 1e-3, and once
//    settled the base carries the weight.
// Both interface modes (tied: constraints per vertex cluster; springs: per node).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cdem/analysis/reactions.hpp"
#include "cdem/io/case.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;
namespace fs = std::filesystem;

constexpr double kP = 1e6;            // Pa on the top
constexpr double kA = 0.1 * 0.1;      // m^2, the bar's section
constexpr double kLoad = kP * kA;     // N

struct BarRun {
  Vec3 reaction;     // on "bottom", last step
  Vec3 load;         // the pressure's force on the top at the end: -p x the current area vector
  double worst_dv;   // largest |v recomputed - v kernel| over the steps (m/s)
  double v_max;      // largest node speed at the end (m/s)
};

// A 0.1 x 0.1 x 1 m bar of tets, bottom fixed, pressure kP on the top; `prestress`: the blocks
// start at sigma_zz = -kP (equilibrium); `damping`: local damping alpha_L.
BarRun static_bar(InterfaceMode mode, bool prestress, double damping, int steps) {
  ScopedThreads one(1);
  BlockMaterial mat = rock(1e10, 0.25, 2500);
  mat.local_damping = damping;
  const Mesh mesh = structured_tet_box(1, 1, 10, {0.1, 0.1, 1.0});
  Model model = build_model(mesh, {mat}, {interface_of(InterfaceLaw::Elastic)}, "static bar");
  Case c = make_case({mat}, {interface_of(InterfaceLaw::Elastic)});
  c.interface_mode = mode;
  BoundaryCondition fixed;
  fixed.faces = "bottom";
  fixed.type = BoundaryType::Fixed;
  BoundaryCondition load;
  load.faces = "top";
  load.type = BoundaryType::Pressure;
  load.value = kP;
  c.boundaries = {fixed, load};
  if (prestress) {
    c.initial_stress.enabled = true;
    c.initial_stress.at_reference = {0, 0, -kP, 0, 0, 0};
  }
  Simulation sim(std::move(model), c);
  ReactionMeter meter(sim.model(), c.boundaries, c.gravity, c.path);
  EXPECT_EQ(meter.face_sets(), std::vector<std::string>{"bottom"});
  BarRun r{{}, {}, 0, 0};
  for (int k = 0; k < steps; ++k) {
    const double t_mid = sim.time() + 0.5 * sim.dt();
    meter.before_step(sim.model());
    sim.step(false);
    r.worst_dv = std::max(r.worst_dv, meter.after_step(sim.model(), sim.dt(), t_mid));
  }
  r.reaction = meter.forces()[0];
  const Model& m = sim.model();
  for (const auto& v : m.v) r.v_max = std::max(r.v_max, norm(v));
  // A follower pressure: on the current faces (the top widens by the Poisson effect under the
  // load, and a mesh of Kuhn tets tilts it slightly, so the load has x and y parts too).
  for (const auto& f : m.facet_set("top")->facets) {
    Vec3 p[3];
    for (int q = 0; q < f.count(); ++q) p[q] = m.x[f.nodes[q]];
    r.load += -kP * face_area_vector(std::span<const Vec3>(p, f.count()), f.count());
  }
  return r;
}

class ReactionForces : public ::testing::TestWithParam<InterfaceMode> {};

TEST_P(ReactionForces, PrestressedBarCarriesTheLoadFromTheFirstStep) {
  for (int steps : {1, 200}) {
    const BarRun r = static_bar(GetParam(), true, 0.0, steps);
    std::printf("[reactions] %s prestressed, %d steps: R = (%.6g, %.6g, %.9g) N, load %.6g N, "
                "|dv| %.2g m/s\n",
                name_of(GetParam()), steps, r.reaction.x, r.reaction.y, r.reaction.z, kLoad, r.worst_dv);
    EXPECT_NEAR(r.reaction.z, kLoad, 1e-6 * kLoad);
    EXPECT_LT(norm(r.reaction + r.load), 1e-6 * kLoad);
    EXPECT_LT(r.worst_dv, 1e-12);
  }
}

TEST_P(ReactionForces, BarLoadedFromRestSettlesToTheLoad) {
  const BarRun r = static_bar(GetParam(), false, 0.8, 30000);
  const double rel = norm(r.reaction + r.load) / norm(r.load);
  std::printf("[reactions] %s loaded from rest, settled: R = (%.6g, %.6g, %.9g) N, load (%.6g, %.6g, "
              "%.9g) N, |R + load| / |load| %.2e (R_z / pA0 - 1 = %.2e, the top's area change), speed "
              "%.2g m/s, |dv| %.2g m/s\n",
              name_of(GetParam()), r.reaction.x, r.reaction.y, r.reaction.z, r.load.x, r.load.y,
              r.load.z, rel, r.reaction.z / kLoad - 1, r.v_max, r.worst_dv);
  EXPECT_LT(rel, 1e-6);
  EXPECT_NEAR(r.reaction.z, kLoad, 1e-4 * kLoad);  // the area grows by 2 nu p / E = 5e-5
  EXPECT_LT(r.worst_dv, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Modes, ReactionForces,
                         ::testing::Values(InterfaceMode::Tied, InterfaceMode::Springs),
                         [](const auto& p) { return std::string(name_of(p.param)); });

// ---- gravity on a heavy model, through cdemblast's run loop ----

std::vector<std::vector<std::string>> read_csv(const std::string& path, std::vector<std::string>* header) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::vector<std::string>> rows;
  bool first = true;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (first) {
      if (header) *header = cells;
      first = false;
    } else {
      rows.push_back(cells);
    }
  }
  return rows;
}

std::size_t column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t k = 0; k < header.size(); ++k)
    if (header[k] == name) return k;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

class HeavyBlock : public ::testing::TestWithParam<const char*> {};

// The issue's 13.6 t cylinder (radius 0.9 m, height 2 m, granite) at rest on a fixed base under
// gravity. Undamped: it stays in free vertical vibration about the sagged state; the energy
// error is asserted over every sample. Damped (local damping 0.6): it settles and the base's
// reaction is the weight M g.
TEST_P(HeavyBlock, UnderGravityOnAFixedBaseDoesNotStop) {
  const std::string mode = GetParam();
  const fs::path dir = fs::temp_directory_path() / ("cdem_heavy_block_" + mode);
  fs::create_directories(dir);
  const std::string path = (dir / "heavy.toml").string();
  std::ofstream(path) << R"(
title = "heavy_block"
[mesh.generate]
shape = "cylinder"
size = [0.9, 0.0, 2.0]
element_size = 0.4
[simulation]
end_time = 2e-3
history_interval = 0
gravity = [0, 0, -9.81]
[[material]]
name = "granite"
regions = ["rock"]
density = 2681
youngs_modulus = 99.3e9
poisson_ratio = 0.28
[[interface]]
name = "bond"
law = "fracture_energy"
tensile_strength = 8.11e6
cohesion = 20e6
friction_angle = 35
dilation_angle = 15
tensile_fracture_energy = 70
shear_fracture_energy = 700
[[boundary]]
faces = "bottom"
type = "fixed"
)";
  for (bool damped : {false, true}) {
    std::vector<std::string> sets = {"simulation.interfaces=\"" + mode + "\""};
    if (damped) {
      sets.push_back("material.0.local_damping=0.8");
      sets.push_back("simulation.end_time=0.01");
      sets.push_back("simulation.history_interval=1e-4");
    }
    const Case c = load_case(path, sets);
    RunOptions opt;
    opt.out_dir = (dir / (damped ? "damped" : "free")).string();
    opt.threads = 1;
    opt.quiet = true;
    const RunResult res = run_case(c, opt);
    EXPECT_EQ(res.status, 0) << res.diagnosis;
    std::vector<std::string> h;
    const auto energy = read_csv(opt.out_dir + "/energy.csv", &h);
    ASSERT_GT(energy.size(), 90u);
    double worst = 0;
    for (const auto& row : energy) worst = std::max(worst, std::stod(row[column(h, "error")]));
    const double gw = std::stod(energy.back()[column(h, "gravity_work")]);
    std::printf("[gravity] %s %s: %zu samples, energy error max %.3g, gravity work %.4g J\n",
                mode.c_str(), damped ? "damped" : "undamped", energy.size(), worst, gw);
    EXPECT_LE(worst, 1e-3);
    EXPECT_GT(gw, 0);
    if (damped) {
      // The weight, from the model's own masses (the cylinder's facets make it 1-2 % lighter
      // than pi r^2 h rho = 13.64 t).
      const auto rows = read_csv(opt.out_dir + "/reactions.csv", &h);
      ASSERT_FALSE(rows.empty());
      const Mesh mesh = load_mesh(c);
      const Model m = build_case_model(c, mesh);
      double mass = 0;
      for (double mm : m.mass) mass += mm;
      const double rz = std::stod(rows.back()[column(h, "fz")]);
      std::printf("[gravity] %s settled: base reaction %.6g N, weight %.6g N (%.2e)\n", mode.c_str(),
                  rz, mass * 9.81, rz / (mass * 9.81) - 1);
      EXPECT_EQ(rows.back()[column(h, "face_set")], "bottom");
      EXPECT_NEAR(rz, mass * 9.81, 1e-3 * mass * 9.81);
    }
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Modes, HeavyBlock, ::testing::Values("tied", "springs"),
                         [](const auto& p) { return std::string(p.param); });

}  // namespace
}  // namespace cdem
