// Verification of the bar's gas bodies (explosive/gas.hpp; docs/theory.md "Bar charges: the gas",
// numbers in docs/verification_gas.md): the collar plug against its 1D force balance, free
// expansion on the adiabat with the work converging to Q rho V0, and the gas mass in cracks
// conserved to round-off in a cracking run.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cdem/explosive/charges.hpp"
#include "cdem/io/case.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/charge_builders.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;
using namespace test_charges;

// ---------------------------------------------------------------------------------------------
// The plug: stemming of length L, mass m = rho_s A L, in a hole of section A and perimeter c,
// wall shear tau on the length still in the hole, pushed by a constant pressure p:
//   m x'' = p A - tau c (L - x)   ->   x(t) = C (cosh(w t) - 1),  w^2 = tau c / m,
//   C = (p A - tau c L) / (tau c), out when x = L: t_out = acosh(1 + L / C) / w.
// advance_plug (semi-implicit Euler, the step's) must eject it at t_out within 5 % (the issue's
// tolerance; the scheme is first order: 1000 steps over t_out give ~0.1 %); below the static
// friction (p A < tau c L) it must not move.
// ---------------------------------------------------------------------------------------------
TEST(GasPlug, EjectionTimeMatchesForceBalance) {
  const double r = 0.02, a = kPi * r * r, c = 2 * kPi * r, len = 0.5, rho_s = 2000, tau = 1e6;
  const double mass = rho_s * a * len, p = 2.0 * tau * c * len / a;  // twice the holding pressure
  const double w = std::sqrt(tau * c / mass), cc = (p * a - tau * c * len) / (tau * c);
  const double t_out = std::acosh(1.0 + len / cc) / w;
  double x = 0, v = 0, t = 0;
  const double dt = t_out / 1000;
  while (!advance_plug(x, v, p, a, c, len, mass, tau, dt)) t += dt;
  t += dt;
  std::printf("[gas plug] ejected at %.5g s, 1D force balance %.5g s (%+.3f %%)\n", t, t_out,
              100 * (t / t_out - 1));
  EXPECT_NEAR(t / t_out, 1.0, 0.05);
  double x2 = 0, v2 = 0;
  for (int k = 0; k < 100; ++k) advance_plug(x2, v2, 0.99 * tau * c * len / a, a, c, len, mass, tau, dt);
  EXPECT_EQ(x2, 0.0);
}

// One gas body of `eos` products (model cavity, V0 = 1 L) sized for a model without interfaces
// (no cracks).
GasField cavity_body(const Eos& eos) {
  GasField g;
  GasBody b;
  b.model = GasModel::Cavity;
  b.eos = 0;
  b.rho_w = explosive_density(eos);
  b.v0 = 1e-3;
  g.bodies = {b};
  init_gas_field(Model{}, g, {});
  return g;
}

// ---------------------------------------------------------------------------------------------
// Free expansion: one gas body (emulsion, Landau, fully burnt) whose cavity grows geometrically
// from V0 to 1e10 V0 with nothing resisting. Its pressure is the adiabat P(V/V0) exactly (the
// body's density is its mass over its volume: checked to 1e-12, far inside the 0.1 %),
// and the work it records, the trapezoidal integral of P dV, converges to the chemical energy
// Q rho V0 (Landau's Pc is the value that makes the work to infinity equal it): within 0.5 % at
// 1e10 V0 with 8000 geometric steps (the trapezoid's error ~ (ln ratio / n)^2 ~ 1e-5; what the
// second stage still holds beyond 1e10 V0 is (1e10)^-(gamma2 - 1) = 5e-4 of its energy; the
// printed analytic work to 1e5 V0 shows the convergence: -1.7 % there).
// ---------------------------------------------------------------------------------------------
TEST(GasBody, FreeExpansionFollowsTheAdiabat) {
  const Eos eos = *builtin_explosive("emulsion");
  GasField g = cavity_body(eos);
  const GasBody b = g.bodies[0];
  Model m;  // no interfaces: no cracks
  AppliedLoads out;
  double worst = 0;
  const int n = 8000;
  for (int k = 0; k <= n; ++k) {
    const double ratio = std::pow(1e10, static_cast<double>(k) / n);
    g.burnt_volume[0] = b.v0;
    g.cavity[0] = ratio * b.v0;
    update_gas(m, g, {eos}, out, 1e-7);
    worst = std::max(worst, std::abs(g.bodies[0].pressure / eos_pressure(eos, ratio) - 1.0));
  }
  const double q = energy_density(eos) * b.v0;
  std::printf("[gas free expansion] pressure against the adiabat: max error %.2e; work to 1e10 V0 "
              "%.6g J, Q rho V0 %.6g J (%+.3f %%; analytic to 1e5 V0: %+.3f %%)\n",
              worst, g.bodies[0].work, q, 100 * (g.bodies[0].work / q - 1),
              100 * (expansion_work(eos, 1.0, 1e5) * b.v0 / q - 1));
  EXPECT_LT(worst, 1e-12);
  EXPECT_NEAR(g.bodies[0].work / q, 1.0, 0.005);
}

// A charge burning in a rigid hole: the cavity is exactly the burnt charge's volume at every
// step, so the products never expand and do no work, however the burnt volume grows (the
// recorded work is 0 to round-off, 1e-12 of Q rho V0; it used to count the volume the new
// products brought as expansion).
TEST(GasBody, BurningInARigidHoleDoesNoWork) {
  const Eos eos = *builtin_explosive("emulsion");
  GasField g = cavity_body(eos);
  const GasBody b = g.bodies[0];
  Model m;
  AppliedLoads out;
  for (int k = 1; k <= 100; ++k) {
    g.burnt_volume[0] = b.v0 * k / 100.0;
    g.cavity[0] = g.burnt_volume[0];
    update_gas(m, g, {eos}, out, 1e-7);
    EXPECT_NEAR(g.bodies[0].pressure / eos_pressure(eos, 1.0), 1.0, 1e-12) << "step " << k;
  }
  const double q = energy_density(eos) * b.v0;
  std::printf("[gas burn in a rigid hole] work %.3g J of Q rho V0 %.6g J\n", g.bodies[0].work, q);
  EXPECT_LE(std::abs(g.bodies[0].work), 1e-12 * q);
}

// ---------------------------------------------------------------------------------------------
// Gas mass in a cracking run (gas = "cracks"): a bar charge in a 1 m plate of 5 cm quads with weak
// Mohr-Coulomb interfaces. At every step the body's burnt mass equals the mass in the cavity plus
// the mass in the cracks plus the vented mass, and the mass in the cracks equals the density times
// the volume of the filled cracks recomputed here from the fill fractions and the apertures:
// both to 1e-12 (round-off of the sums; the issue asks 1e-12 until venting). The run must crack
// and fill cracks, or the check is empty.
// ---------------------------------------------------------------------------------------------
TEST(GasCracks, MassConservedInTheCracks) {
  Mesh mesh = quad_grid(20, 20, 1.0, 1.0);
  std::vector<BlockMaterial> mats{rock()};
  std::vector<InterfaceMaterial> ifs{interface_of(InterfaceLaw::MohrCoulomb, 2e6, 6e6, 30)};
  HoleDef h = bar("g", {0.475, 0.3, 0}, {0.475, 0.7, 0}, 0.05);
  h.gas = GasModel::Cracks;
  Case c = charge_case(mats, ifs, {h});
  Model model = build_model(mesh, mats, ifs, "gas test");
  BarCharges bc = build_bar_charges(model, charge_spec(c));
  const double dt_bar = make_charge_cavities(model, bc);
  Simulation sim(std::move(model), c);
  sim.limit_dt(dt_bar, "bar blocks");
  sim.add_load([&bc](Model& mm, AppliedLoads& out, double t) { bar_loads(mm, bc, out, t); });
  double worst_total = 0, worst_cracks = 0, m_cr_max = 0;
  for (int k = 0; k < 200; ++k) {
    sim.step();
    const Model& m = sim.model();
    const GasBody& gb = bc.gas.bodies[0];
    const double mgas = gb.gas_mass(), vol = gb.volume();
    if (!(vol > 0) || !(mgas > 0)) continue;
    const double rho = mgas / vol;
    // the filled cracks' volume, independently
    double vcr = 0;
    const int np = m.springs_per_iface;
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      if (bc.gas.iface_body[i] != 0) continue;
      bool open = true;
      for (int q = 0; q < np; ++q) open = open && !m.sp_tied[i * np + q];
      if (!open) continue;
      double w = 0;
      for (int q = 0; q < np; ++q)
        w += dot(m.x[m.sp_b[i * np + q]] - m.x[m.sp_a[i * np + q]], m.iface_normal[i]);
      w /= np;
      if (w > 0) vcr += bc.gas.iface_fill[i] * np * m.sp_area.v[i] * w;
    }
    const double in_cavity = rho * (gb.v_cavity + gb.v_plug);
    worst_total = std::max(worst_total, std::abs(in_cavity + gb.m_cracks + gb.vented - gb.burnt) / gb.burnt);
    worst_cracks = std::max(worst_cracks, std::abs(gb.m_cracks - rho * vcr) / mgas);
    m_cr_max = std::max(m_cr_max, gb.m_cracks / mgas);
  }
  std::printf("[gas cracks] 200 steps: up to %.1f %% of the gas in cracks; mass balance error %.2e, "
              "crack mass against its recomputed volume %.2e\n",
              100 * m_cr_max, worst_total, worst_cracks);
  EXPECT_GT(m_cr_max, 0.01) << "no gas reached the cracks";
  EXPECT_LT(worst_total, 1e-12);
  EXPECT_LT(worst_cracks, 1e-12);
}

}  // namespace
}  // namespace cdem
