// Materials as small value types. Block materials give the elastic constants of eq. (6);
// interface materials give the spring laws of eq. (7) and SPEC 1.3.
#pragma once
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace cdem {

struct BlockMaterial {
  std::string name;
  double density = 0;        // kg/m^3
  double youngs = 0;         // Pa
  double poisson = 0;        // -
  double damping = 0;        // mass-proportional viscous damping mu_d / m (1/s), eq. (3)
  double local_damping = 0;  // non-viscous local damping alpha_L (-), 0..1
  double stiffness_damping = 0;  // Rayleigh beta (s): viscous stress beta C:E' (physics/stiffness_damping.hpp)
  std::string explosive;     // non-empty: the region is a solid charge of this explosive
  // Bar charges (make_charge_cavities): the share of the block that is charge, min(1, phi),
  // and whether the block counts as charge (phi >= 0.5: glued to its neighbours, left out of
  // fragments, grading and funnel like a solid charge's blocks).
  double charge_fraction = 0;
  bool charge_block = false;
  // The share of the block's mass that is the charge's products (a bar charge block:
  // phi rho_w / rho_c, set with charge_fraction); an explosive block's is 1.
  double products_mass = 0;
  double products_fraction() const { return explosive.empty() ? products_mass : 1.0; }
  // The rock volume fraction of a block of this material (0 for explosive / charge blocks).
  double rock_fraction() const {
    return (!explosive.empty() || charge_block) ? 0.0 : 1.0 - charge_fraction;
  }
  std::vector<std::string> regions;

  double shear() const { return youngs / (2.0 * (1.0 + poisson)); }
  double lambda() const { return youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)); }
  double bulk() const { return youngs / (3.0 * (1.0 - 2.0 * poisson)); }
  // P-wave speed c_p = sqrt(E (1-nu) / ((1+nu)(1-2nu) rho)) (SPEC 1.1); S-wave sqrt(G/rho).
  double cp() const { return std::sqrt((lambda() + 2.0 * shear()) / density); }
  double cs() const { return std::sqrt(shear() / density); }
};

enum class InterfaceLaw { MohrCoulomb = 0, FractureEnergy = 1, Elastic = 2 };
inline const char* name_of(InterfaceLaw l) {
  return l == InterfaceLaw::MohrCoulomb ? "mohr_coulomb"
         : l == InterfaceLaw::FractureEnergy ? "fracture_energy" : "elastic";
}

struct InterfaceMaterial {
  std::string name;
  InterfaceLaw law = InterfaceLaw::MohrCoulomb;
  double tensile_strength = 0;  // f_t (Pa)
  double cohesion = 0;          // c (Pa)
  double friction_deg = 0;      // phi
  double residual_friction_deg = -1;  // phi_r after breaking; < 0 means "same as phi"
  double dilation_deg = 0;      // psi (fracture-energy law)
  double gt = 0;                // G_t, tensile fracture energy (J/m^2 = Pa.m)
  double gs = 0;                // G_s, shear fracture energy (J/m^2)
  double stiffness_factor = 10; // alpha in k_n = alpha E / h
  bool precracked = false;      // joint: spring points start broken (contact only)
  std::vector<std::pair<std::string, std::string>> pairs;  // region pairs it applies to
  bool is_default = false;      // applies to every region pair not listed elsewhere

  double residual_friction() const {
    return residual_friction_deg < 0 ? friction_deg : residual_friction_deg;
  }
};

// Interface law parameters as the spring kernel uses them (per unit area, radians -> tan).
struct SpringLaw {
  InterfaceLaw law = InterfaceLaw::MohrCoulomb;
  double ft = 0, c = 0;           // Pa
  double tan_phi = 0, tan_phi_r = 0, tan_psi = 0;
  double wc = 0, sc = 0;          // m: w_c = 2 G_t / f_t0, s_c = 2 G_s / c0
};

inline SpringLaw make_spring_law(const InterfaceMaterial& m) {
  constexpr double deg = 3.14159265358979323846 / 180.0;
  SpringLaw s;
  s.law = m.law;
  s.ft = m.tensile_strength;
  s.c = m.cohesion;
  s.tan_phi = std::tan(m.friction_deg * deg);
  s.tan_phi_r = std::tan(m.residual_friction() * deg);
  s.tan_psi = std::tan(m.dilation_deg * deg);
  s.wc = m.tensile_strength > 0 ? 2.0 * m.gt / m.tensile_strength : 0.0;
  s.sc = m.cohesion > 0 ? 2.0 * m.gs / m.cohesion : 0.0;
  return s;
}

}  // namespace cdem
