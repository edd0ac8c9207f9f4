// Verification: 1D P-wave in a long bar of CDEM blocks joined by unbreakable elastic springs.
//
// Set-up (plane strain, unit thickness): a bar of nx x ny square quads of side h along x,
// rollers (v_y = 0) on the top and bottom faces, a pressure p0 on the left end rising linearly
// to p0 over t_r and then held, the right end free (its reflection never reaches the
// measurement points in the simulated time). The interfaces use the 'elastic' law with
// stiffness factor alpha: k_n = alpha E / h per unit area (h = sqrt(A) of the square blocks).
//
// Expected wave speed (long-wave limit of the discrete bar, derived here for this set-up):
// along x every cell is a block of length h in series with one normal spring point pair, so the
// axial compliance of a cell is the sum of the block's and the spring's:
//   h / M_cell = h / M_lat + 1 / k_n   ->   1 / M_cell = 1 / M_lat + 1 / (alpha E).
// M_lat is the block's axial modulus under the lateral condition of the set-up. With rollers
// on y = 0 and y = H and ny rows, the ny - 1 horizontal interfaces between rows are springs in
// series with the blocks across the height; sigma_yy is uniform across the rows (lateral
// equilibrium) and the total lateral displacement is zero:
//   ny h eps_yy + (ny - 1) h sigma_yy / (alpha E) = 0  ->  eps_yy = -c_l sigma_yy,
//   c_l = (ny - 1) / (ny alpha E).
// With the plane-strain block law sigma_xx = M eps_xx + lambda eps_yy,
// sigma_yy = lambda eps_xx + M eps_yy (M = lambda + 2 G, the P-wave modulus):
//   sigma_yy = lambda eps_xx / (1 + M c_l),  M_lat = M - lambda^2 c_l / (1 + M c_l).
// (ny = 1 gives M_lat = M exactly: the 1D-strain condition.) Then c_eff = sqrt(M_cell / rho);
// the stress behind the front is -p0 (traction continuity) and the particle velocity
// v = p0 / (rho c_eff) (momentum balance across the front, impedance rho c_eff).
// SPEC 1.3 quotes this as 1/E_eff = 1/E + 1/(k_n h): the same series-spring rule.
//
// Measurement: two monitor blocks at x1 and x2 (block stress sampled every step); the arrival
// time is when -sigma_xx first reaches p0 / 2 (linear interpolation between steps). The load
// rises linearly over 40 cell transit times, so the front is long compared with the cells: its
// half level travels at the long-wave speed, up to a shift by the lattice dispersion that is
// of second order in h / (ramp length) (measured below); the ramp's own delay cancels in
// t2 - t1. The speed is (x2 - x1) / (t2 - t1).
// Each test runs its own simulations (CTest starts one process per test); a simulation is
// cached within a process.
// Results are tabulated in docs/verification_waves_lame.md.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cdem/analysis/monitors.hpp"
#include "cdem/io/case.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/model/materials.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {
namespace {

// Rock of SPEC 5.1: E 10 GPa, nu 0.25, rho 2500 kg/m3 (M = 12 GPa, c_p = 2190.9 m/s).
constexpr double kE = 10e9, kNu = 0.25, kRho = 2500.0;
constexpr double kP0 = 1e6;  // Pa: strain ~1e-4, geometric non-linearity negligible (1e-4)

// nx x ny square quads of side h from the origin; face sets left, right, bottom, top.
Mesh bar_mesh(int nx, int ny, double h) {
  Mesh m;
  m.dim = 2;
  m.region_names = {"rock"};
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.vertices.push_back({i * h, j * h, 0.0});
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.elem_type.push_back(ElemType::Quad4);
      m.elem_vertices.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)});
      m.elem_region.push_back(0);
      m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
    }
  FaceSet left{"left", {}}, right{"right", {}}, bottom{"bottom", {}}, top{"top", {}};
  for (int j = 0; j < ny; ++j) {
    left.facets.push_back({{vid(0, j + 1), vid(0, j), -1}});
    right.facets.push_back({{vid(nx, j), vid(nx, j + 1), -1}});
  }
  for (int i = 0; i < nx; ++i) {
    bottom.facets.push_back({{vid(i, 0), vid(i + 1, 0), -1}});
    top.facets.push_back({{vid(i + 1, ny), vid(i, ny), -1}});
  }
  m.face_sets = {left, right, bottom, top};
  check_mesh(m, "test_waves bar");
  return m;
}

struct WaveResult {
  double c_measured = 0;     // m/s
  double c_predicted = 0;    // m/s, series-spring formula above
  double sigma_plateau = 0;  // Pa, mean sigma_xx behind the front at x1 (expected -p0)
  double v_measured = 0;     // m/s, mean particle velocity behind the front at x1
  double v_predicted = 0;    // p0 / (rho c_eff)
  double dt = 0;
  std::int64_t steps = 0;
  std::size_t blocks = 0;
  double wall_s = 0;
};

// alpha > 0: springs mode with k_n = alpha E / h; alpha = 0: tied mode (the interfaces are
// exact ties, the bar is the conforming quad mesh: c_eff = c_p, the series formula with
// alpha -> infinity).
WaveResult run_bar(double alpha) {
  const auto wall0 = std::chrono::steady_clock::now();
  // h = 1 cm, 2 m long (200 cells), 2 rows: 400 blocks.
  const int nx = 200, ny = 2;
  const double h = 0.01, length = nx * h;
  const double x1 = 0.505, x2 = 1.505;  // block centres (columns 50 and 150)

  BlockMaterial rock;
  rock.name = "rock";
  rock.regions = {"rock"};
  rock.density = kRho;
  rock.youngs = kE;
  rock.poisson = kNu;
  InterfaceMaterial bond;
  bond.name = "bond";
  bond.law = InterfaceLaw::Elastic;
  const bool tied = alpha == 0;
  bond.stiffness_factor = tied ? 10.0 : alpha;
  bond.is_default = true;

  // Prediction (see the header comment).
  const double lam = rock.lambda(), M = rock.lambda() + 2 * rock.shear();
  const double cl = tied ? 0.0 : (ny - 1) / (ny * alpha * kE);
  const double m_lat = M - lam * lam * cl / (1 + M * cl);
  const double m_cell = tied ? m_lat : 1.0 / (1.0 / m_lat + 1.0 / (alpha * kE));
  WaveResult r;
  r.c_predicted = std::sqrt(m_cell / kRho);
  r.v_predicted = kP0 / (kRho * r.c_predicted);

  // Ramp over 40 cell transits (0.18 ms, 0.4 m of bar): long enough that the lattice
  // dispersion hardly moves the half level (measured on a 3 m bar: speed error +0.33 % with a
  // 20-cell ramp, +0.07 % with 40 cells: second order in h / ramp length; here -0.1 %), short
  // compared with the 0.46 ms the front takes from x1 to x2.
  const double t_ramp = 40 * h / rock.cp();
  Case c;
  c.path = "test_waves (in-code case)";
  c.title = "p_wave_bar";
  c.dt_safety = 0.5;
  c.materials = {rock};
  c.interfaces = {bond};
  c.interface_mode = tied ? InterfaceMode::Tied : InterfaceMode::Springs;
  BoundaryCondition load;
  load.faces = "left";
  load.type = BoundaryType::Pressure;
  load.value = kP0;
  load.table.points = {{0.0, 0.0}, {t_ramp, 1.0}};
  BoundaryCondition top, bottom;
  top.faces = "top";
  top.type = BoundaryType::Roller;
  bottom.faces = "bottom";
  bottom.type = BoundaryType::Roller;
  c.boundaries = {load, top, bottom};

  Simulation sim(build_model(bar_mesh(nx, ny, h), c.materials, c.interfaces, c.path), c);
  const Model& m = sim.model();
  const auto b1 = find_block(m, {x1, 0.5 * h, 0});
  const auto b2 = find_block(m, {x2, 0.5 * h, 0});
  EXPECT_GE(b1, 0);
  EXPECT_GE(b2, 0);
  if (b1 < 0 || b2 < 0) return r;

  // Simulated time: the half level reaches x2 at ~0.82 ms (x2 / c_eff + t_ramp / 2); the
  // reflection from the free right end comes back to x2 at (2 L - x2) / c, >= 1.14 ms even at
  // c_p (an upper bound of c_eff), after the end (1.0 ms).
  const double t_end = 1.0e-3;
  EXPECT_LT(t_end, (2 * length - x2) / rock.cp());
  double t1 = -1, t2 = -1, prev1 = 0, prev2 = 0, prev_t = 0;
  double v_sum = 0, s_sum = 0;
  std::int64_t n_avg = 0;
  while (sim.time() < t_end) {
    const double t_state = sim.time();  // stresses after this step are at t_n = this time
    sim.step();
    const double s1 = -m.stress[b1][0], s2 = -m.stress[b2][0];
    if (t1 < 0 && s1 >= 0.5 * kP0 && t_state > 0)
      t1 = prev_t + (t_state - prev_t) * (0.5 * kP0 - prev1) / (s1 - prev1);
    if (t2 < 0 && s2 >= 0.5 * kP0 && t_state > 0)
      t2 = prev_t + (t_state - prev_t) * (0.5 * kP0 - prev2) / (s2 - prev2);
    // Plateau at x1: from 0.2 ms after the half-level arrival (the rest of the ramp, 0.09 ms,
    // plus the front's spread) to the end (~0.47 ms of plateau); the reflection reaches x1 only
    // at (2 L - x1) / c >= 1.6 ms.
    if (t1 > 0 && t_state > t1 + 0.2e-3) {
      v_sum += sample_block(m, b1).velocity.x;
      s_sum += m.stress[b1][0];
      ++n_avg;
    }
    prev1 = s1;
    prev2 = s2;
    prev_t = t_state;
  }
  EXPECT_GT(t1, 0) << "the front never reached x1";
  EXPECT_GT(t2, 0) << "the front never reached x2";
  EXPECT_GT(n_avg, 100) << "plateau window too short";
  if (t1 > 0 && t2 > 0) r.c_measured = (x2 - x1) / (t2 - t1);
  if (n_avg > 0) {
    r.v_measured = v_sum / n_avg;
    r.sigma_plateau = s_sum / n_avg;
  }
  r.dt = sim.dt();
  r.steps = sim.steps();
  r.blocks = m.n_blocks();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf(
      "[p-wave alpha=%g (0: tied)] blocks %zu, dt %.4g s (%s), steps %lld, wall %.2f s\n"
      "  c_measured %.2f m/s, c_eff predicted %.2f m/s (c_p %.2f), error %+.3f %%\n"
      "  v_measured %.5f m/s, predicted %.5f m/s, error %+.3f %%; sigma_xx plateau %.5g Pa\n",
      alpha, r.blocks, r.dt, sim.stable().limit.c_str(), static_cast<long long>(r.steps), r.wall_s,
      r.c_measured, r.c_predicted, rock.cp(), 100 * (r.c_measured / r.c_predicted - 1),
      r.v_measured, r.v_predicted, 100 * (r.v_measured / r.v_predicted - 1), r.sigma_plateau);
  return r;
}

const WaveResult& result(double alpha) {
  if (alpha == 0.0) {
    static const WaveResult r0 = run_bar(0.0);
    return r0;
  }
  if (alpha == 10.0) {
    static const WaveResult r10 = run_bar(10.0);
    return r10;
  }
  static const WaveResult r100 = run_bar(100.0);
  return r100;
}

// Checks of one run.
// - Wave speed against the series-spring c_eff. Tolerance 0.5 %: the half-level arrival of the
//   ramp is a long-wave measure; the lattice dispersion moves it by a second-order amount in
//   h / ramp length (measured -0.11 % at alpha = 10, -0.08 % at alpha = 100 with this 40-cell
//   ramp; +0.33 % with a 20-cell one), and the sampling error is below dt / (t2 - t1) = 0.1 %.
//   0.5 % is tighter than the brief's "a few %" and than the gap between c_eff and c_p (5.8 %
//   at alpha = 10, 0.63 % at alpha = 100), so the check tells c_eff from c_p.
// - Behind the front: sigma_xx = -p0 (traction continuity at the loaded end) and
//   v = p0 / (rho c_eff) (momentum balance across the front). Both hold exactly for the
//   discrete bar once the front has passed; the lattice ringing behind the ramp oscillates
//   about the plateau, and the ~0.5 ms average is within 0.01 % (measured). Tolerance 0.5 %:
//   well above that, below the 5.8 % by which rho c_p would miss v at alpha = 10.
// - Run size (the brief: a few thousand blocks, < 5 s): the block and step counts (about 1800
//   and 5700 steps), not the machine-dependent wall time, which is only printed.
void check_run(double alpha) {
  const auto& r = result(alpha);
  EXPECT_NEAR(r.c_measured / r.c_predicted, 1.0, 0.005) << "wave speed, alpha " << alpha;
  EXPECT_NEAR(r.sigma_plateau / -kP0, 1.0, 0.005) << "plateau stress, alpha " << alpha;
  EXPECT_NEAR(r.v_measured / r.v_predicted, 1.0, 0.005) << "particle velocity, alpha " << alpha;
  EXPECT_LE(r.blocks, 5000u);
  EXPECT_LT(r.steps, 10000);
}

TEST(PWaveBar, Alpha10MatchesSeriesSprings) { check_run(10.0); }

// Tied interfaces: the bar is the conforming mesh, c_eff = c_p (same tolerances and reasons).
TEST(PWaveBar, TiedMatchesContinuum) { check_run(0.0); }

TEST(PWaveBar, Alpha100MatchesSeriesSprings) { check_run(100.0); }

// The alpha dependence: c(10) / c(100) against the formula (0.948). The measurement's own
// systematic error (dispersion of the same ramp on the same lattice) is nearly the same in
// both runs and cancels in the ratio (measured: 0.03 % off); 0.5 % (the brief asks ~1 %)
// checks the 5.2 % effect of alpha to a tenth of itself.
TEST(PWaveBar, SpeedRatioFollowsAlpha) {
  const auto& a = result(10.0);
  const auto& b = result(100.0);
  const double measured = a.c_measured / b.c_measured;
  const double predicted = a.c_predicted / b.c_predicted;
  std::printf("[p-wave] c(10)/c(100): measured %.5f, predicted %.5f\n", measured, predicted);
  EXPECT_NEAR(measured / predicted, 1.0, 0.005);
}

}  // namespace
}  // namespace cdem
