// Equations of state of detonation products, shared by bar charges (SPEC section 2) and
// solid charges (SPEC section 3). Both give the pressure of the burnt gas as a function of
// the relative volume v = V / V0 (V0 the charge's initial volume), on the expansion
// isentrope that starts from the fully burnt charge at v = 1. Small value types, chosen once
// per explosive and visited once per group: no virtual call in a loop.
//
// Derivations, sources and test results: docs/theory_eos.md.
#pragma once
#include <cmath>
#include <string>
#include <string_view>
#include <variant>

namespace cdem {

// Two-stage Landau (Landau-Stanyukovich) isentrope of the detonation products, SPEC eq. 10-11
// (Landau & Lifshitz, Fluid Mechanics, ch. XIV; Henrych, The Dynamics of Explosion and Its
// Use, 1979):
//   P0 = rho_w D^2 / (2 (gamma1 + 1))                   explosion-state pressure, half P_CJ
//   Pc = P0 {(gamma2-1)/(gamma1-gamma2) [(gamma1-1) Q_w rho_w / P0 - 1]}^(gamma1/(gamma1-1))
//   vc = Vc / V0 = (P0 / Pc)^(1/gamma1)
//   P(v) = P0 v^-gamma1            for v <= vc  (P >= Pc, dense products)
//   P(v) = Pc (vc / v)^gamma2      for v >  vc  (P <  Pc, ideal-gas-like products)
// Pc is the one value for which the work of the expansion from v = 1 to infinity equals the
// chemical energy Q_w rho_w per unit charge volume. Build with make(), which checks the data.
struct LandauEos {
  double rho_w = 0.0;         // explosive density, kg/m^3
  double D = 0.0;             // detonation velocity, m/s
  double Q_w = 0.0;           // detonation heat (chemical energy) per unit mass, J/kg
  double gamma1 = 3.0;        // isentropic exponent of the first (high-pressure) stage
  double gamma2 = 4.0 / 3.0;  // isentropic exponent of the second (low-pressure) stage
  double P0 = 0.0;            // derived: pressure at v = 1, Pa
  double Pc = 0.0;            // derived: pressure at the stage change, Pa
  double vc = 0.0;            // derived: relative volume at the stage change, Vc / V0

  // Validates the data and fills the derived constants. Throws InputError naming `where`
  // (e.g. "case.toml: explosive 'emulsion'") and saying which quantity is wrong and why.
  static LandauEos make(double rho_w, double D, double Q_w, double gamma1, double gamma2,
                        const std::string& where);

  // Pressure (Pa) at relative volume v = V / V0. Valid for v > 0 (v < 1 is a compressed
  // charge: the first-stage isentrope is continued). A non-positive v is an inverted
  // charge: it carries no pressure (returns 0); the caller reports it.
  double pressure(double v) const {
    if (!(v > 0.0)) return 0.0;
    if (v <= vc) return P0 * std::pow(v, -gamma1);
    return Pc * std::pow(vc / v, gamma2);
  }
};

// Jones-Wilkins-Lee (JWL) products, Lee, Hornig & Kury 1968 (UCRL-50422); parameter sets from
// Dobratz & Crawford, LLNL Explosives Handbook (UCRL-52997, 1985). The full JWL EOS is
//   P(v, E) = A (1 - omega/(R1 v)) e^(-R1 v) + B (1 - omega/(R2 v)) e^(-R2 v) + omega E / v
// with E the internal energy per unit initial volume. Its isentropes are exactly
//   P_s(v) = A e^(-R1 v) + B e^(-R2 v) + C v^-(1+omega),
//   E_s(v) = A/R1 e^(-R1 v) + B/R2 e^(-R2 v) + C/omega v^-omega   (dE_s/dv = -P_s),
// one per value of C. The charge follows the isentrope through the constant-volume burnt
// state (v = 1, E = E0), the state a programmed (instantaneous, in-place) burn produces:
//   C = omega (E0 - A/R1 e^-R1 - B/R2 e^-R2),
// so the expansion work from v = 1 to infinity is exactly E0, as for the Landau model (and
// as in hydrocodes that start a programmed-burn JWL charge at v = 1 with E = E0). The CJ
// state (P_cj, v_cj) and the constant C_cj of the CJ isentrope are derived as well, from the
// tangency of the Rayleigh line P = rho0 D^2 (1 - v) with an isentrope of the family (the
// conditions Lee, Hornig & Kury fit C with); they are reported, not used for the pressure.
struct JwlEos {
  double rho0 = 0.0;   // explosive density, kg/m^3
  double D = 0.0;      // detonation velocity, m/s
  double A = 0.0;      // Pa
  double B = 0.0;      // Pa
  double R1 = 0.0;     // -
  double R2 = 0.0;     // -
  double omega = 0.0;  // Grueneisen coefficient of the products, -
  double E0 = 0.0;     // detonation energy per unit initial volume, Pa = J/m^3
  double C = 0.0;      // derived: constant of the E0 isentrope used for the pressure, Pa
  double P_cj = 0.0;   // derived: CJ pressure (Rayleigh line / isentrope tangency), Pa
  double v_cj = 0.0;   // derived: CJ relative volume, -
  double C_cj = 0.0;   // derived: constant of the CJ isentrope, Pa

  // Validates the data and fills the derived constants. Throws InputError naming `where`.
  static JwlEos make(double rho0, double D, double A, double B, double R1, double R2, double omega,
                     double E0, const std::string& where);

  // Pressure (Pa) on the E0 isentrope at relative volume v = V / V0 (v > 0); a non-positive
  // v is an inverted charge and returns 0.
  double pressure(double v) const {
    if (!(v > 0.0)) return 0.0;
    return A * std::exp(-R1 * v) + B * std::exp(-R2 * v) + C * std::pow(v, -(1.0 + omega));
  }

  // Energy per unit initial volume (J/m^3) left on the E0 isentrope at v: the work the
  // products can still do expanding from v to infinity. energy(1) = E0.
  double energy(double v) const {
    return A / R1 * std::exp(-R1 * v) + B / R2 * std::exp(-R2 * v) +
           C / omega * std::pow(v, -omega);
  }

  // Relative mismatch between the energy of the CJ isentrope at the CJ point and the
  // Rankine-Hugoniot energy there, E0 + P_cj (1 - v_cj) / 2. A consistent parameter set gives
  // well under 1 % (TNT of Dobratz & Crawford: 0.09 %), at worst about 15 %; make() refuses
  // more than 50 %, which means A, B, R1, R2, omega, E0 and D do not belong together (e.g. a
  // unit slip). Between a few percent and 50 % a case validator may warn.
  double cj_energy_mismatch() const {
    const double e_isentrope = A / R1 * std::exp(-R1 * v_cj) + B / R2 * std::exp(-R2 * v_cj) +
                               C_cj / omega * std::pow(v_cj, -omega);
    const double e_hugoniot = E0 + 0.5 * P_cj * (1.0 - v_cj);
    return e_isentrope / e_hugoniot - 1.0;
  }
};

using Eos = std::variant<LandauEos, JwlEos>;

// Pressure (Pa) of the products at relative volume v = V / V0.
inline double eos_pressure(const Eos& eos, double v) {
  return std::visit([v](const auto& e) { return e.pressure(v); }, eos);
}

// Pressure applied at v = 1 once the charge is fully burnt (Landau: P0; JWL: P_s(1)), Pa.
double initial_pressure(const Eos& eos);

// Chapman-Jouguet pressure, Pa. Landau: rho_w D^2 / (gamma1 + 1) = 2 P0. JWL: the tangency
// point of the Rayleigh line with the isentrope family (computed in JwlEos::make).
double cj_pressure(const Eos& eos);

// Work of the products per unit charge volume V0 expanding from v_from to v_to (J/m^3):
// the integral of P dv. Analytic for both models. v_to may be +infinity. Signed: negative
// when v_to < v_from (compression).
double expansion_work(const Eos& eos, double v_from, double v_to);

// Total chemical energy per unit charge volume, J/m^3: Landau Q_w rho_w, JWL E0.
double energy_density(const Eos& eos);

// Detonation velocity D (m/s) and density (kg/m^3) of the explosive.
double detonation_velocity(const Eos& eos);
double explosive_density(const Eos& eos);

// "landau" or "jwl", the key a case file uses for the model.
std::string_view eos_kind(const Eos& eos);

}  // namespace cdem
