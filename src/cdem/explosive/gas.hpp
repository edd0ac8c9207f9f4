// The bar's detonation products as gas bodies (`[[hole]] gas = "cavity"` or `"cracks"`; SPEC 2
// literal is gas = "literal"; docs/theory.md "Bar charges: the gas").
//
// Each deck is one gas body: its burnt mass m = rho_w sum_i xi_i V_i (V_i the charge volume a
// bound block i holds, xi_i its burnt fraction, eq. 12-13) fills one volume at one pressure
// (equalised along the deck):
//   V = sum_i xi_i [V_i + (J_i - 1) V0_i V_i / V_i,all]     the cavity: the charge plus the whole
//                                                          volume change of its bound blocks
//                                                          (the rock around is far stiffer than
//                                                          the gas: what the block gains in volume
//                                                          is the gas's), shared by the bars in
//                                                          the block by their charge volumes
//     + sum_cracks f_k A_k w_k                             the gas-filled cracks (model cracks)
//     + A_h x_p                                            the hole behind the moving plug
//   P = EOS(rho_w V / (m - m_vented))                      the isentrope (Landau or JWL) at the
//                                                          gas's specific volume
// Cracks (model cracks): an interface none of whose points is tied (intact) with a mean normal
// opening w_k > 0, next to a block the deck's gas has reached (its bound blocks to start with),
// fills at the speed of the choked flow c* = sqrt(gamma P / rho) (2 / (gamma + 1))^((gamma + 1)
// / (2 (gamma - 1))): its fill fraction f_k rises by c* dt / L_c per step; when full, the gas
// has reached the block beyond. A filled crack's faces are pushed apart by f_k P. Mass is
// conserved exactly: the gas has one density, rho = m / V, the crack mass is rho sum f A w.
// Venting, choked, at the rate C_d A_v rho c*: through the collar once the plug is out (or from
// ignition when the deck reaches the collar), A_v the hole's section, and through filled cracks
// that reach a block with a boundary face, A_v = w_k sqrt(A_k) (2D: w_k x 1 m).
// Plug: the collar stemming, mass rho_s A_h L_s, moves under P A_h against the wall shear
// tau_s (perimeter) (L_s - x) of its length still in the hole; out at x = L_s. Stemming between
// decks holds (not modelled).
#pragma once
#include "cdem/explosive/charges.hpp"

namespace cdem {

// The choked mass flux per unit vent area (kg/(m^2 s)) of gas at pressure p and density rho with
// isentropic exponent gamma.
double choked_mass_flux(double p, double rho, double gamma);

// The isentropic exponent of the products at relative volume v (Landau: gamma1 or gamma2 by
// stage; JWL: 1 + omega).
double products_gamma(const Eos& eos, double v);

// One step of the plug of a deck: gas pressure p, hole section a (m^2), perimeter c (m); advances
// x, v over dt and returns true once it is out (x >= length).
bool advance_plug(double& x, double& v, double p, double a, double c, double length, double mass,
                  double shear, double dt);

// Updates every deck with gas model cavity or cracks: burnt mass, volume, pressure, venting,
// plug, the gas-filled cracks and their loads (added through `out`), and the segments' pressure
// seg_p = xi P (the bound blocks are loaded by bar_loads from it). Segments' burnt fractions
// seg_xi must be current. dt: the time since the last call (0 the first time).
void update_deck_gas(Model& m, BarCharges& bc, AppliedLoads& out, double dt);

}  // namespace cdem
