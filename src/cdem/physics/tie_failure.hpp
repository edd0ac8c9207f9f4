// Failure of tied interfaces (simulation.interfaces = "tied", docs/theory.md "Tied
// interfaces"): a tied spring point carries no spring force, so it is tested with the traction
// the two adjacent blocks put on its face,
//   t = 1/2 (sigma_A + sigma_B) n,  F_n = (t . n) A_c (tension positive),  F_s = (t - t_n n) A_c,
// with n the interface's current unit normal (from A to B) and sigma the blocks' Cauchy stresses
// of this step (block_forces has run). The strength test is the interface law's own, at its
// intact strength (tie_strength_exceeded):
//   brittle Mohr-Coulomb: tension F_n >= f_t A_c, else shear |F_s| >= c A_c - F_n tan(phi);
//   fracture energy (extrinsic): the same peak test; the point is then inserted as a cohesive
//     point at its peak strength with zero opening and softens from there (springs.hpp);
//   elastic: never breaks.
// A point that fails is untied (ties.hpp) and starts as a spring point carrying the force it
// carried as a tie, so the blocks feel no jump: its offset g0 = F_n / (k_n A_c) gives
// F_n = k_n A_c (d_n + g0) at d_n = 0, and F_s is set. Mohr-Coulomb: broken at once, F_n the
// compressive part only (a tensile break releases the load: brittle), F_s capped by Coulomb
// friction. Fracture energy: F_n <= f_t A_c, |F_s| <= the shear strength. The elastic energy the
// new spring holds, F_n^2 / (2 k_n A_c) + |F_s|^2 / (2 k_s A_c), did not exist before (the tie
// was rigid): it is returned as the insertion energy of the energy balance. The force is added
// to the two nodes' f in this step (integrate_tied runs after).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// The law's intact strength test for a tie carrying F_n (N, tension positive) and |F_s|^2 (N^2)
// over area A_c (m^2). Returns kModeNone (holds), kModeTension or kModeShear.
std::uint8_t tie_strength_exceeded(const SpringLaw& law, double fn, double fs2, double area);

// Tests every interface with a tied point that can break (Model::iface_check), unties those
// that fail (in ascending interface order, serially: deterministic) and returns the insertion
// energy (J). `flag` is a per-interface work array (sized at set-up by the caller). `terms`, when
// given, is set to the insertion energy's terms in the order summed: (spring point, J).
double tie_failure(Model& m, double t, std::vector<std::uint8_t>& flag,
                   std::vector<std::pair<std::int64_t, double>>* terms = nullptr);

}  // namespace cdem
