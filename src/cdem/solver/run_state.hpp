// What a checkpoint holds (docs/checkpoint.md): the state of every object the run loop steps,
// listed once per object for both saving and loading (StateArchive is symmetric). What set-up
// rebuilds the same from the case and the mesh (reference geometry, topology, materials, the
// charges' binding) is not stored; what any step may change is.
#pragma once
#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/io/checkpoint.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {

void io_state(StateArchive& ar, Model& m);
void io_state(StateArchive& ar, ContactSet& cs);
void io_state(StateArchive& ar, GasField& g, const std::string& prefix);
void io_state(StateArchive& ar, BarCharges& bars);
void io_state(StateArchive& ar, SolidCharges& solids);

}  // namespace cdem
