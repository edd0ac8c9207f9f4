// Equations of state of detonation products: data checks, derived constants, energies.
// Formulas and sources are in eos.hpp and docs/theory_eos.md.
#include "cdem/explosive/eos.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "cdem/core/error.hpp"

namespace cdem {
namespace {

// Every EOS datum is a strictly positive, finite number; NaN fails the test too.
void require_positive(double x, const char* name, const char* unit, const std::string& where) {
  if (!(x > 0.0) || !std::isfinite(x)) {
    throw InputError(fmt::format("{}: {} = {:g} {} is invalid: expected a positive finite number",
                                 where, name, x, unit));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Landau two-stage isentrope (SPEC eq. 10-11)

LandauEos LandauEos::make(double rho_w, double D, double Q_w, double gamma1, double gamma2,
                          const std::string& where) {
  require_positive(rho_w, "density rho_w", "kg/m^3", where);
  require_positive(D, "detonation velocity D", "m/s", where);
  require_positive(Q_w, "detonation heat Q_w", "J/kg", where);
  require_positive(gamma1, "gamma1", "", where);
  require_positive(gamma2, "gamma2", "", where);
  // gamma2 > 1 keeps the energy of the second stage finite (its tail integral is
  // Pc vc / (gamma2 - 1)); gamma1 > gamma2 is what makes two stages (and the bracket's
  // denominator positive).
  if (!(gamma2 > 1.0)) {
    throw InputError(fmt::format(
        "{}: gamma2 = {:g} is invalid: expected gamma2 > 1 (the second-stage expansion to "
        "infinite volume would release infinite energy)",
        where, gamma2));
  }
  if (!(gamma1 > gamma2)) {
    throw InputError(fmt::format(
        "{}: gamma1 = {:g} must be greater than gamma2 = {:g}: the Landau EOS has a stiff "
        "first stage (typically gamma1 = 3) and a soft second stage (typically 4/3)",
        where, gamma1, gamma2));
  }

  LandauEos e;
  e.rho_w = rho_w;
  e.D = D;
  e.Q_w = Q_w;
  e.gamma1 = gamma1;
  e.gamma2 = gamma2;
  e.P0 = rho_w * D * D / (2.0 * (gamma1 + 1.0));

  // Energy closure: P0/(g1-1) + Pc vc (g1-g2)/((g1-1)(g2-1)) = Q_w rho_w, with
  // Pc vc = P0^(1/g1) Pc^((g1-1)/g1), gives Pc = P0 * bracket^(g1/(g1-1)).
  const double energy = Q_w * rho_w;  // J/m^3
  const double bracket =
      (gamma2 - 1.0) / (gamma1 - gamma2) * ((gamma1 - 1.0) * energy / e.P0 - 1.0);
  if (!(bracket > 0.0)) {
    throw InputError(fmt::format(
        "{}: detonation heat Q_w = {:g} J/kg is too small for D = {:g} m/s and gamma1 = {:g}: "
        "the first-stage expansion from P0 = rho_w D^2/(2 (gamma1+1)) = {:.4g} Pa alone "
        "releases P0/(gamma1-1) = {:.4g} J/m^3, more than the chemical energy Q_w rho_w = "
        "{:.4g} J/m^3, so no energy is left for the second stage (the bracket (gamma2-1)/"
        "(gamma1-gamma2) [(gamma1-1) Q_w rho_w/P0 - 1] = {:.4g} is not positive). Check Q_w "
        "(J/kg) and D (m/s).",
        where, Q_w, D, gamma1, e.P0, e.P0 / (gamma1 - 1.0), energy, bracket));
  }
  if (!(bracket < 1.0)) {
    // bracket >= 1 means Pc >= P0: even a single gamma2 stage starting at P0 cannot release
    // Q_w rho_w (it releases P0/(gamma2-1)); the two-stage isentrope does not exist.
    throw InputError(fmt::format(
        "{}: detonation heat Q_w = {:g} J/kg is too large for D = {:g} m/s and gamma2 = {:g}: "
        "the chemical energy Q_w rho_w = {:.4g} J/m^3 exceeds P0/(gamma2-1) = {:.4g} J/m^3, "
        "the most a gamma2 expansion from P0 = {:.4g} Pa can release, so the stage-change "
        "pressure Pc would exceed P0. Check Q_w (J/kg), D (m/s) and gamma2.",
        where, Q_w, D, gamma2, energy, e.P0 / (gamma2 - 1.0), e.P0));
  }
  e.Pc = e.P0 * std::pow(bracket, gamma1 / (gamma1 - 1.0));
  e.vc = std::pow(e.P0 / e.Pc, 1.0 / gamma1);
  return e;
}

namespace {

// Work (J/m^3 of charge) the Landau products still do expanding from v to infinity.
//   v >= vc: integral of Pc (vc/v')^g2 dv' = Pc vc (vc/v)^(g2-1) / (g2-1)
//   v <  vc: P0/(g1-1) (v^(1-g1) - vc^(1-g1)) + Pc vc/(g2-1)
double landau_remaining_work(const LandauEos& e, double v) {
  if (std::isinf(v)) return 0.0;
  const double tail = e.Pc * e.vc / (e.gamma2 - 1.0);
  if (v >= e.vc) return tail * std::pow(e.vc / v, e.gamma2 - 1.0);
  return e.P0 / (e.gamma1 - 1.0) * (std::pow(v, 1.0 - e.gamma1) - std::pow(e.vc, 1.0 - e.gamma1)) +
         tail;
}

// ---------------------------------------------------------------------------------------------
// JWL: CJ state from the Rayleigh line / isentrope tangency (Lee, Hornig & Kury 1968)

// Constant C of the isentrope whose slope at v equals the Rayleigh slope -rho0 D^2:
//   -dP_s/dv = A R1 e^(-R1 v) + B R2 e^(-R2 v) + (1+omega) C v^-(2+omega) = rho0 D^2.
double tangent_isentrope_constant(const JwlEos& e, double rho_d2, double v) {
  return std::pow(v, 2.0 + e.omega) / (1.0 + e.omega) *
         (rho_d2 - e.A * e.R1 * std::exp(-e.R1 * v) - e.B * e.R2 * std::exp(-e.R2 * v));
}

// Gap between that isentrope and the Rayleigh line P = rho0 D^2 (1 - v) at v; zero at CJ.
double tangency_gap(const JwlEos& e, double rho_d2, double v) {
  const double c = tangent_isentrope_constant(e, rho_d2, v);
  const double p_s =
      e.A * std::exp(-e.R1 * v) + e.B * std::exp(-e.R2 * v) + c * std::pow(v, -(1.0 + e.omega));
  return p_s - rho_d2 * (1.0 - v);
}

}  // namespace

JwlEos JwlEos::make(double rho0, double D, double A, double B, double R1, double R2, double omega,
                    double E0, const std::string& where) {
  require_positive(rho0, "density rho0", "kg/m^3", where);
  require_positive(D, "detonation velocity D", "m/s", where);
  require_positive(A, "A", "Pa", where);
  require_positive(B, "B", "Pa", where);
  require_positive(R1, "R1", "", where);
  require_positive(R2, "R2", "", where);
  require_positive(omega, "omega", "", where);
  require_positive(E0, "E0", "J/m^3", where);
  if (!(R1 > R2)) {
    throw InputError(fmt::format(
        "{}: JWL R1 = {:g} must be greater than R2 = {:g} (A, R1 is the high-pressure term, "
        "B, R2 the intermediate one; were they swapped?)",
        where, R1, R2));
  }

  JwlEos e;
  e.rho0 = rho0;
  e.D = D;
  e.A = A;
  e.B = B;
  e.R1 = R1;
  e.R2 = R2;
  e.omega = omega;
  e.E0 = E0;

  // Isentrope through (v = 1, E = E0): E_s(1) = E0.
  const double ab_energy = A / R1 * std::exp(-R1) + B / R2 * std::exp(-R2);
  e.C = omega * (E0 - ab_energy);
  if (!(e.C > 0.0)) {
    throw InputError(fmt::format(
        "{}: JWL E0 = {:.4g} J/m^3 is too small: the A and B terms alone hold {:.4g} J/m^3 at "
        "v = 1, leaving no energy for the omega term (C = omega (E0 - A/R1 e^-R1 - B/R2 e^-R2) "
        "= {:.4g} Pa <= 0). E0 is the detonation energy per unit initial volume (Pa = J/m^3): "
        "a value in J/kg must be multiplied by the density.",
        where, E0, ab_energy, e.C));
  }

  // CJ point: scan v downward from 1 for the first sign change of the tangency gap with a
  // positive isentrope constant, then bisect to machine precision.
  const double rho_d2 = rho0 * D * D;
  const int n_scan = 2000;
  const double v_min = 0.02;
  double v_hi = 1.0;
  double g_hi = tangency_gap(e, rho_d2, v_hi);
  double v_lo = 0.0;
  bool found = false;
  for (int i = 1; i <= n_scan; ++i) {
    const double v = 1.0 - (1.0 - v_min) * i / n_scan;
    const double g = tangency_gap(e, rho_d2, v);
    if ((g <= 0.0) != (g_hi <= 0.0) && tangent_isentrope_constant(e, rho_d2, v) > 0.0 &&
        tangent_isentrope_constant(e, rho_d2, v_hi) > 0.0) {
      v_lo = v;
      found = true;
      break;
    }
    v_hi = v;
    g_hi = g;
  }
  if (!found) {
    throw InputError(fmt::format(
        "{}: JWL data have no Chapman-Jouguet point for D = {:g} m/s: no isentrope P = A "
        "e^-R1v + B e^-R2v + C v^-(1+omega) with C > 0 is tangent to the Rayleigh line "
        "P = rho0 D^2 (1 - v) = {:.4g} (1 - v) Pa for 0.02 < v < 1. Check A, B (Pa), rho0 "
        "(kg/m^3) and D (m/s).",
        where, D, rho_d2));
  }
  const double g_lo_sign = tangency_gap(e, rho_d2, v_lo) <= 0.0 ? -1.0 : 1.0;
  for (int it = 0; it < 200 && v_hi - v_lo > 4.0 * std::numeric_limits<double>::epsilon(); ++it) {
    const double v_mid = 0.5 * (v_lo + v_hi);
    const double g = tangency_gap(e, rho_d2, v_mid);
    if ((g <= 0.0 ? -1.0 : 1.0) == g_lo_sign) {
      v_lo = v_mid;
    } else {
      v_hi = v_mid;
    }
  }
  e.v_cj = 0.5 * (v_lo + v_hi);
  e.P_cj = rho_d2 * (1.0 - e.v_cj);
  e.C_cj = tangent_isentrope_constant(e, rho_d2, e.v_cj);

  // Published sets close the CJ energy balance to a fraction of a percent (TNT, PETN, Comp B,
  // C-4, ANFO) and at worst about 15 % (HMX); a mismatch of more than 50 % can only come from
  // data that do not belong together (typically a unit slip in A, B or E0, which gives
  // factors, or D from another density), so it is refused rather than run.
  const double mismatch = e.cj_energy_mismatch();
  if (!(std::abs(mismatch) <= 0.5)) {
    throw InputError(fmt::format(
        "{}: JWL data are inconsistent: at the CJ point (P_cj = {:.4g} Pa, v_cj = {:.4g}, "
        "from D = {:g} m/s and rho0 = {:g} kg/m^3) the energy of the isentrope, {:.4g} J/m^3, "
        "differs by {:.0f} % from the Rankine-Hugoniot energy E0 + P_cj (1 - v_cj)/2 = {:.4g} "
        "J/m^3 (published sets agree to within about 15 %). Check the units of A, B (Pa) and E0 "
        "(J/m^3) and that D and rho0 belong to the same parameter set.",
        where, e.P_cj, e.v_cj, D, rho0, (1.0 + mismatch) * (E0 + 0.5 * e.P_cj * (1.0 - e.v_cj)),
        100.0 * mismatch, E0 + 0.5 * e.P_cj * (1.0 - e.v_cj)));
  }
  return e;
}

// ---------------------------------------------------------------------------------------------
// Functions on the variant

namespace {
template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;
}  // namespace

double initial_pressure(const Eos& eos) {
  return std::visit(Overloaded{[](const LandauEos& e) { return e.P0; },
                               [](const JwlEos& e) { return e.pressure(1.0); }},
                    eos);
}

double cj_pressure(const Eos& eos) {
  return std::visit(
      Overloaded{[](const LandauEos& e) { return e.rho_w * e.D * e.D / (e.gamma1 + 1.0); },
                 [](const JwlEos& e) { return e.P_cj; }},
      eos);
}

double expansion_work(const Eos& eos, double v_from, double v_to) {
  return std::visit(Overloaded{[&](const LandauEos& e) {
                                 return landau_remaining_work(e, v_from) -
                                        landau_remaining_work(e, v_to);
                               },
                               [&](const JwlEos& e) {
                                 const double w_to = std::isinf(v_to) ? 0.0 : e.energy(v_to);
                                 const double w_from = std::isinf(v_from) ? 0.0 : e.energy(v_from);
                                 return w_from - w_to;
                               }},
                    eos);
}

double energy_density(const Eos& eos) {
  return std::visit(Overloaded{[](const LandauEos& e) { return e.Q_w * e.rho_w; },
                               [](const JwlEos& e) { return e.E0; }},
                    eos);
}

double detonation_velocity(const Eos& eos) {
  return std::visit([](const auto& e) { return e.D; }, eos);
}

double explosive_density(const Eos& eos) {
  return std::visit(Overloaded{[](const LandauEos& e) { return e.rho_w; },
                               [](const JwlEos& e) { return e.rho0; }},
                    eos);
}

std::string_view eos_kind(const Eos& eos) {
  return std::visit(Overloaded{[](const LandauEos&) { return std::string_view{"landau"}; },
                               [](const JwlEos&) { return std::string_view{"jwl"}; }},
                    eos);
}

}  // namespace cdem
