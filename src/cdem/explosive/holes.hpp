// The holes and their charges as plain data (SPEC 2): what a case's [[hole]] and [[explosive]]
// tables say once they are read and validated (io/case.cpp), and what the explosive models are
// built from (explosive/charges.hpp). No file and no case here.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/explosive/eos.hpp"
#include "cdem/explosive/gas_model.hpp"

namespace cdem {

// A named explosive: a built-in one or one given in [[explosive]].
struct ExplosiveDef {
  std::string name;
  Eos eos;
};

// One charge (deck) of a hole, placed from the bottom up (SPEC 2).
struct Deck {
  std::string explosive;    // name of an ExplosiveDef
  double length = 0;        // m
  double delay = 0;         // initiation time t_D0 (s) = the group's delay + own_delay
  double own_delay = 0;     // the deck's own `delay` key (s)
  bool initiate_top = false;  // default: initiated at the deck's bottom
  Vec3 bottom, top;         // derived end points
  Vec3 initiation() const { return initiate_top ? top : bottom; }
};

enum class ChargeModel { Bar, Solid };

struct HoleDef {
  std::string name;
  std::string group;        // delay group ("" none): its [delays] entry adds to every deck's delay
  Vec3 collar, end;         // collar (top) and bottom of the hole
  double diameter = 0;      // m
  ChargeModel model = ChargeModel::Bar;
  double attenuation_exponent = 1.25;  // a in (r0 / L_c)^a (bar model)
  bool cavity = true;       // bar model: the charge's share of a bound element is not rock
  bool lc_element_size = false;  // bar model: L_c in (r0/L_c)^a is the element size (SPEC read
                                 // literally), not its equivalent radius about the bar
  GasModel gas = GasModel::Cracks;   // bar model: the products' volume and venting
  double stemming_density = 2000;    // kg/m^3, the collar stemming plug
  double stemming_shear_strength = 1e6;  // Pa, wall shear stress resisting the plug
  double vent_coefficient = 1.0;     // discharge coefficient of the choked vents
  std::vector<Deck> decks;
  std::vector<std::pair<double, double>> stemming;  // (from, to) distances from the bottom (m)
  double length() const { return norm(collar - end); }
};

// What the explosive models are built from: the holes, the explosives they name, and the face
// sets the products cannot vent through (those under a fixed, roller, non-reflecting or velocity
// condition: more rock or a wall beyond; free and pressure-loaded faces vent). The set-up makes it
// from a validated case (charge_spec, io/case.hpp).
struct ChargeSpec {
  std::string path;  // the case file the holes were read from (named in errors)
  std::vector<HoleDef> holes;
  std::vector<ExplosiveDef> explosives;
  std::vector<std::string> closed_face_sets;
  const ExplosiveDef* explosive(const std::string& name) const {
    for (const auto& e : explosives)
      if (e.name == name) return &e;
    return nullptr;
  }
};

}  // namespace cdem
