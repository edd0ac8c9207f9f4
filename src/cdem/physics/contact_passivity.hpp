// Contact passivity (ContactSettings::passivity; docs/theory.md "General contact"): the dashpot
// that takes back the energy a node's contacts made. Used by the node-to-face forces
// (contact.cpp (c)); the debt is booked in its node-side gather.
#pragma once
#include <algorithm>
#include <cmath>

namespace cdem {

// Passivity (ContactSettings::passivity). A penalty spring can give back only what the motion
// stored in it, but an explicit step can make energy: a node that leaves the spring within a step
// is kicked by its last force for the whole step (k d v dt where the spring held k d^2 / 2), and
// a push handed from one block to another restarts from a depth the node did not push in. Both
// show as a pair's booked dissipation (the work done on it less its stored energy's change)
// below zero. Each node keeps the energy its contacts made and have not taken back, its debt D:
// at each step its contacts book D = max(0, D - sum of their dissipation). While D > 0, a node in
// contact gets a normal dashpot c = min(D / (2 v_n^2 dt), kPassivityZeta 2 sqrt(k m),
// kPassivityStep m / dt) on top of the contact's own damping, which takes D back over the next
// steps (the time-domain passivity observer and controller of Hannaford and Ryu, IEEE Trans.
// Robotics and Automation 18(1), 2002, per contact node). Half the debt per step: the work of a
// step's force is booked half at that step and half at the next (the trapezoid above), so aiming
// at the whole debt took about 1.5 times it (1.27 in the test), half takes about 1.05 times it.
// A contact that made nothing is not touched. kPassivityZeta = 0.5 keeps the dashpot below
// critical and the explicit step stable for it (the central-difference bound
// 2 (sqrt(1 + zeta^2) - zeta) / omega = 1.24 / omega against omega dt <= 1 of the penalty's
// share of the step budget).
constexpr double kPassivityZeta = 0.5;
// ... and it takes at most this share of the node's normal speed relative to the face in one step
// (c dt <= kPassivityStep m): a dashpot on the lagged velocity that takes more overshoots, and
// near rest flips the relative velocity's sign every step.
constexpr double kPassivityStep = 0.25;

// The normal dashpot coefficient (N s/m) added to a node's contact with debt D (J) > 0 moving at
// v_n relative to the face (penalty k, node mass m, step dt).
inline double passivity_dashpot(double debt, double vn, double dt, double k, double mass) {
  return std::min({0.5 * debt / (vn * vn * dt), kPassivityZeta * 2.0 * std::sqrt(k * mass), kPassivityStep * mass / dt});
}

}  // namespace cdem
