// Built-in explosives. The data go through the same checks (LandauEos::make, JwlEos::make) as
// a user's data, so a typo here fails every test that touches the library.
#include "cdem/explosive/explosive_library.hpp"

#include <algorithm>
#include <cctype>
#include <string_view>

namespace cdem {
namespace {

struct Entry {
  std::string_view name;
  std::string_view source;
};

constexpr Entry kEntries[] = {
    {"emulsion",
     "emulsion explosive, Landau EOS: rho 1150 kg/m^3, D 5000 m/s, Q 3.1e6 J/kg, gamma1 3.0, "
     "gamma2 1.33 (SPEC 5.1, single-hole cut blasting case of the method's paper)"},
    {"rdx",
     "RDX-like explosive, Landau EOS: rho 1820 kg/m^3, D 8350 m/s, Q 5.4e6 J/kg, gamma1 3.0, "
     "gamma2 1.33 (SPEC 5.3, pile foundation pit case of the method's paper)"},
    {"tnt_jwl",
     "TNT, JWL EOS: rho0 1630 kg/m^3, D 6930 m/s, A 371.2 GPa, B 3.231 GPa, R1 4.15, R2 0.95, "
     "omega 0.30, E0 7.0 GPa, P_CJ 21.0 GPa (Dobratz & Crawford, LLNL Explosives Handbook, "
     "UCRL-52997, 1985)"},
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

std::optional<Eos> builtin_explosive(const std::string& name) {
  const std::string key = lower(name);
  const std::string where = "built-in explosive '" + key + "'";
  if (key == "emulsion") return Eos{LandauEos::make(1150.0, 5000.0, 3.1e6, 3.0, 1.33, where)};
  if (key == "rdx") return Eos{LandauEos::make(1820.0, 8350.0, 5.4e6, 3.0, 1.33, where)};
  if (key == "tnt_jwl") {
    return Eos{JwlEos::make(1630.0, 6930.0, 371.2e9, 3.231e9, 4.15, 0.95, 0.30, 7.0e9, where)};
  }
  return std::nullopt;
}

std::vector<std::string> builtin_explosive_names() {
  std::vector<std::string> names;
  for (const Entry& e : kEntries) names.emplace_back(e.name);
  return names;
}

std::optional<std::string> builtin_explosive_source(const std::string& name) {
  const std::string key = lower(name);
  for (const Entry& e : kEntries) {
    if (e.name == key) return std::string(e.source);
  }
  return std::nullopt;
}

}  // namespace cdem
