// Energy conservation of the explicit solver (SPEC 1.1, 4) in undamped elastic vibration of
// free bodies with unbreakable (elastic) interfaces, run through Simulation with a Case built
// in code. Over at least 20 periods of the excited fundamental (axial) mode:
//  - total mechanical energy (kinetic + block strain + spring strain) stays within 0.5 % of the
//    initial energy;
//  - the run's own energy balance error (Simulation::energy().error) stays small.
// Numbers are recorded in docs/verification_core.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cdem/solver/simulation.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;

struct VibrationResult {
  double e0 = 0;           // reference mechanical energy (J): initial, or at the end of the pulse
  double max_dev = 0;      // max |E(t) - E0| / E0 over the samples (after the pulse)
  double final_dev = 0;    // (E(end) - E0) / E0
  double max_shadow = 0;   // max |E*(t) - E*(t0)| / E0, E* the leapfrog invariant (see below)
  double max_balance = 0;  // max Simulation::energy().error during free vibration
  double max_balance_load = 0;  // the same while the pulse acts
  double max_artefact = 0;      // max of 1/8 sum m |v(n+1/2) - v(n-1/2)|^2 / E0
  double periods = 0;           // fundamental periods covered (counted from the length signal)
  double period = 0;            // measured period (s)
  double input = 0;             // external work of the pulse (J)
  std::int64_t steps = 0;
  double dt = 0;
  std::string limit;
};

enum class Start { Stretch, Velocity, Pulse };

// Free bar along x, excited in its first axial mode (ends moving in opposition), in one of
// three ways:
//  - Velocity: v = v0 cos(pi (X - x0) / L) e_x, the free-free mode shape (no initial stress);
//  - Pulse: a smooth pressure pulse p(t) = p0 sin^2(pi t / T_p) on both end faces for
//    T_p = 0.4 ms (about half the fundamental period), then free vibration;
//  - Stretch: released from a uniform stretch x = c + (1 + eps0) (X - c) of all nodes.
// The bar length (mean x of the right end minus the left end) oscillates about its rest value;
// its crossings count the periods.
//
// Energies sampled at step n (Simulation::energy): kinetic 1/2 m |v_mid|^2 with
// v_mid = (v(n-1/2) + v(n+1/2)) / 2, strain at x(n). For a linear system the central-difference
// scheme conserves exactly E*_n = 1/2 m v(n-1/2).v(n+1/2) + strain(x_n) (the leapfrog
// invariant); the sampled total exceeds it by the artefact 1/8 sum m |v(n+1/2) - v(n-1/2)|^2 =
// 1/8 dt^2 sum |f|^2 / m, of relative size (omega dt)^2 / 8 per mode. Both are recorded.
VibrationResult vibrate(const Mesh& mesh, Start start, double n_periods_min, double dt_safety) {
  const auto mat = rock(1e10, 0.25, 2500);
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Model model = make_model(mesh, mat, glue);
  const BarEnds ends(model);
  const double x0 = ends.x0, len = ends.len;
  Vec3 c{};
  for (const auto& p : model.X_nodes()) c += p;
  c = c / static_cast<double>(model.n_nodes());
  const double eps0 = 1e-4, v0 = 0.1, p0 = 1e6, t_pulse = 4e-4;
  double e_kin0 = 0;
  Case cs = make_case({mat}, {glue}, dt_safety);
  if (start == Start::Stretch) {
    for (std::size_t n = 0; n < model.n_nodes(); ++n)
      model.x[n].x = c.x + (1 + eps0) * (model.X(n).x - c.x);
  } else if (start == Start::Velocity) {
    for (std::size_t n = 0; n < model.n_nodes(); ++n) {
      model.v[n] = {v0 * std::cos(kPi * (model.X(n).x - x0) / len), 0, 0};
      e_kin0 += 0.5 * model.mass[n] * dot(model.v[n], model.v[n]);
    }
  } else {
    TimeTable table;
    table.points.clear();
    for (int k = 0; k <= 200; ++k) {
      const double t = t_pulse * k / 200;
      table.points.push_back({t, std::pow(std::sin(kPi * t / t_pulse), 2)});
    }
    for (const char* side : {"left", "right"}) {
      BoundaryCondition bc;
      bc.faces = side;
      bc.type = BoundaryType::Pressure;
      bc.value = p0;
      bc.table = table;
      cs.boundaries.push_back(bc);
    }
  }
  Simulation sim(std::move(model), cs);
  VibrationResult r;
  r.dt = sim.dt();
  r.limit = sim.stable().limit;
  const double t_free = start == Start::Pulse ? t_pulse : 0.0;  // free vibration from here
  // Initial energy computed here, independently of Simulation's own book-keeping: the kinetic
  // energy of the velocity field, or the strain energy of the stretched state (no velocity).
  r.e0 = start == Start::Velocity ? e_kin0 : sim.energy().mechanical();
  double prev = ends.length_change(sim.model());
  int crossings = 0;
  double t_first = -1, t_last = -1, shadow0 = 0;
  bool free_started = false;
  std::vector<Vec3> v_before;
  const std::int64_t max_steps = 200000;
  while (sim.steps() < max_steps) {
    const bool sample = sim.steps() % 5 == 0;
    if (sample) v_before = sim.model().v;
    sim.step(sample);
    const bool is_free = sim.time() > t_free;
    const double now = ends.length_change(sim.model());
    if (is_free && (prev < 0) != (now < 0)) {
      ++crossings;
      if (t_first < 0) t_first = sim.time();
      t_last = sim.time();
    }
    prev = now;
    if (!sample) continue;
    const EnergyBalance e = sim.energy();
    if (!is_free) {
      r.max_balance_load = std::max(r.max_balance_load, e.error);
      continue;
    }
    r.max_balance = std::max(r.max_balance, e.error);
    const Model& m = sim.model();
    double shadow = e.block_strain + e.spring_strain, artefact = 0;
    for (std::size_t n = 0; n < m.n_nodes(); ++n) {
      shadow += 0.5 * m.mass[n] * dot(v_before[n], m.v[n]);
      const Vec3 dv = m.v[n] - v_before[n];
      artefact += 0.125 * m.mass[n] * dot(dv, dv);
    }
    if (!free_started) {
      free_started = true;
      if (start == Start::Pulse) {
        r.e0 = e.mechanical();
        r.input = e.external_work;
      }
      shadow0 = start == Start::Pulse ? shadow : r.e0;
    }
    const double dev = (e.mechanical() - r.e0) / r.e0;
    r.max_dev = std::max(r.max_dev, std::abs(dev));
    r.final_dev = dev;
    r.max_shadow = std::max(r.max_shadow, std::abs(shadow - shadow0) / r.e0);
    r.max_artefact = std::max(r.max_artefact, artefact / r.e0);
    // Stop one period past the minimum (two crossings per period).
    if (crossings >= 2 * n_periods_min + 3) break;
  }
  r.steps = sim.steps();
  r.period = crossings > 1 ? 2 * (t_last - t_first) / (crossings - 1) : 0;
  r.periods = r.period > 0 ? (sim.time() - t_free) / r.period : 0;
  return r;
}

void report(const char* what, const VibrationResult& r) {
  std::printf(
      "[energy] %-15s %6lld steps (dt %.3e s, %s), %.1f periods of %.4e s: max |E-E0|/E0 "
      "%.2e (end %+.2e), |E*-E*0|/E0 %.2e, artefact %.2e, balance error %.2e (during "
      "the load %.2e)\n",
      what, static_cast<long long>(r.steps), r.dt, r.limit.c_str(), r.periods, r.period, r.max_dev,
      r.final_dev, r.max_shadow, r.max_artefact, r.max_balance, r.max_balance_load);
}

struct Body {
  const char* name;
  Mesh mesh;
  double continuum_period;  // 2 L / c of the free-free bar: 2D plane-strain strip with free
                            // faces, c = sqrt(E / (rho (1 - nu^2))); 3D thin bar c = sqrt(E / rho)
};
std::vector<Body> bodies() {
  const double c2 = std::sqrt(1e10 / (2500 * (1 - 0.25 * 0.25))), c3 = std::sqrt(1e10 / 2500);
  return {{"quad 8x2", quad_grid(8, 2, 0.8, 0.2), 2 * 0.8 / c2},
          {"tri 8x2x2", tri_grid(8, 2, 0.8, 0.2), 2 * 0.8 / c2},
          {"tet 6x1x1x6", tet_box(6, 1, 1, 0.6, 0.1, 0.1), 2 * 0.6 / c3}};
}

// Tolerances.
// - Total mechanical energy within 0.5 % of the initial (the brief's criterion). The sampled
//   total differs from the conserved invariant E* by the artefact (omega dt)^2 / 8 per mode;
//   a smooth (low-mode) start keeps it at a few 1e-4 with the default safety 0.5.
// - Invariant E*: exactly conserved by central differences for a linear system; the
//   co-rotational blocks and current-normal springs are nonlinear at the order of the strain,
//   here v0 / c = 0.1 / 2000 = 5e-5 (velocity start) and 1e-4 (pulse: p0 / E). Tolerance 1e-4 of
//   E0 bounds a drift of that order (over 20 periods, no secular growth allowed beyond it).
constexpr double kEnergyTol = 5e-3;
constexpr double kInvariantTol = 1e-4;
constexpr double kPeriodsMin = 20;

// Smooth start (the free-free mode's velocity field), default time step.
TEST(Energy, FreeVibrationFromModeVelocity) {
  ScopedThreads one(1);
  for (const auto& b : bodies()) {
    const auto r = vibrate(b.mesh, Start::Velocity, kPeriodsMin, 0.5);
    report(b.name, r);
    std::printf("[energy]   period / continuum 2L/c = %.4f\n", r.period / b.continuum_period);
    EXPECT_GE(r.periods, kPeriodsMin) << b.name;
    EXPECT_LT(r.max_dev, kEnergyTol) << b.name;
    EXPECT_LT(r.max_shadow, kInvariantTol) << b.name;
    // The measured period must be the bar's axial one: slower than the continuum by the
    // interface compliance only (alpha = 10 adds 1/alpha of compliance per interface crossed,
    // a few interfaces per cell at most): within [1, 1.5] x 2L/c.
    EXPECT_GT(r.period / b.continuum_period, 1.0) << b.name;
    EXPECT_LT(r.period / b.continuum_period, 1.5) << b.name;
  }
}

// The initial kinetic energy of a Model given to Simulation with a velocity field must count
// as initial energy in the run's balance (SPEC 4: the error tells the user whether to trust
// the run). Velocity start as in FreeVibrationFromModeVelocity, one period; tolerance 0.5 % as
// for the total energy (the balance compares the same sampled total with the initial energy).
TEST(Energy, InitialVelocityCountsInBalance) {
  ScopedThreads one(1);
  const auto r = vibrate(quad_grid(8, 2, 0.8, 0.2), Start::Velocity, 1, 0.5);
  std::printf(
      "[energy] velocity start: Simulation::energy().error max %.3e (total energy "
      "deviation %.2e)\n",
      r.max_balance, r.max_dev);
  EXPECT_LT(r.max_balance, kEnergyTol);
}

// Energy put in by a smooth pressure pulse on both ends (external work counted by Simulation),
// then free vibration: the run's own balance error and the total energy stay small.
// Simulation::energy().error during free vibration: tolerance 0.5 % as for the total energy
// (it is the same sampled total compared with the recorded input work).
TEST(Energy, PressurePulseThenFreeVibration) {
  ScopedThreads one(1);
  for (const auto& b : bodies()) {
    const auto r = vibrate(b.mesh, Start::Pulse, kPeriodsMin, 0.5);
    report(b.name, r);
    std::printf("[energy]   energy at the end of the pulse / input work - 1 = %.2e\n",
                r.e0 / r.input - 1);
    EXPECT_GE(r.periods, kPeriodsMin) << b.name;
    EXPECT_GT(r.input, 0) << b.name;
    EXPECT_LT(r.max_dev, kEnergyTol) << b.name;
    EXPECT_LT(r.max_balance, kEnergyTol) << b.name;
    EXPECT_LT(r.max_shadow, kInvariantTol) << b.name;
  }
}

// Released from a uniform stretch of all nodes: the blocks are stressed but the springs are not
// (coincident nodes coincide), so every split node pair starts out of equilibrium and the
// high-frequency interface ("breathing") modes are excited with a large share of the energy.
// The integrator still conserves the invariant E* (asserted); the sampled total then carries
// the (omega dt)^2 / 8 artefact of those modes: 1-2 % at safety 0.5 (recorded in the docs, not
// a conservation error: E_sampled - E* = 1/8 sum m |dv|^2 exactly).
TEST(Energy, StretchReleaseConservesInvariant) {
  ScopedThreads one(1);
  for (const auto& b : bodies()) {
    const auto r = vibrate(b.mesh, Start::Stretch, kPeriodsMin, 0.5);
    report(b.name, r);
    EXPECT_GE(r.periods, kPeriodsMin) << b.name;
    EXPECT_LT(r.max_shadow, kInvariantTol) << b.name;
    // The sampled deviation is the artefact (to the invariant's drift).
    EXPECT_LE(r.max_dev, r.max_artefact + r.max_shadow) << b.name;
  }
}

}  // namespace
}  // namespace cdem
