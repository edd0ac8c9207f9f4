#pragma once
// The run's checks of its state (run_checks.cpp).
#include <string>

#include "cdem/io/case.hpp"
#include "cdem/model/model.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

// The energy scale below which the blow-up check does not compare (1/2 (1e-8)^2 sum E V).
double energy_floor(const Model& m);

// A diagnosis when the state is not finite, a block is inverted, the energy has blown up
// (mechanical energy > factor x the energy put in, or x floor), the contacts made energy (their
// booked dissipation below -contact_limit x it) or the interfaces did (their booked dissipation
// more than iface_limit x it below fracture_peak); else "". A limit of 0 is not checked.
std::string check_stability(const Simulation& sim, const EnergyBalance& e, double factor,
                            double contact_limit, double iface_limit, double fracture_peak, double t,
                            double floor);

// When no finite stable time step exists, throws an InputError saying which material or block
// makes it so; returns otherwise.
void diagnose_time_step(const Model& m, const Case& c);

}  // namespace cdem
