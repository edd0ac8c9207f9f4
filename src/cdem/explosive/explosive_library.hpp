// Named explosives a case file can refer to instead of giving the EOS data. Each entry states
// its source; see docs/theory_eos.md for the numbers it derives (P0, P_CJ, Pc, vc, C).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "cdem/explosive/eos.hpp"

namespace cdem {

// The built-in explosive `name` (matched without regard to case), or nothing if unknown:
//   "emulsion"  Landau, rho 1150 kg/m^3, D 5000 m/s, Q 3.1e6 J/kg, gamma1 3, gamma2 1.33
//               (SPEC 5.1)
//   "rdx"       Landau, rho 1820 kg/m^3, D 8350 m/s, Q 5.4e6 J/kg, gamma1 3, gamma2 1.33
//               (SPEC 5.3, RDX-like)
//   "tnt_jwl"   JWL TNT, rho0 1630 kg/m^3, D 6930 m/s, A 371.2 GPa, B 3.231 GPa, R1 4.15,
//               R2 0.95, omega 0.30, E0 7.0 GPa (Dobratz & Crawford 1985)
std::optional<Eos> builtin_explosive(const std::string& name);

// The names builtin_explosive() knows, in a fixed order (for help texts and error messages).
std::vector<std::string> builtin_explosive_names();

// One line saying what the entry is and where its numbers come from; nothing if unknown.
std::optional<std::string> builtin_explosive_source(const std::string& name);

}  // namespace cdem
