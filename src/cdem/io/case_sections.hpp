// The sections of a case file that parse_case (case.cpp) reads in files of their own, one per
// concept: [mesh] (case_mesh.cpp), [[material]] and [[interface]] (case_materials.cpp),
// [[explosive]], [[hole]] and [delays] (case_charges.cpp). For the case*.cpp files only. Each
// fills its part of the Case and throws InputError naming the file and the key.
#pragma once
#include <string>

#include "cdem/io/case.hpp"
#include "cdem/io/toml_reader.hpp"

namespace cdem {

// [mesh]: the mesh file (relative to the case's directory) or [mesh.generate], whose mesh is
// sized before anything is meshed.
void parse_mesh(const TomlTable& top, Case& c);

// [[material]] (at least one) and [[interface]].
void parse_materials(const TomlTable& top, Case& c);

// Refuses t[key] = rho (kg/m^3) when no solid has that density, warns when it looks like
// another unit (materials and explosives).
void check_density(const TomlTable& t, const std::string& key, double rho);

// [[explosive]] and [[hole]], after the materials (the built-in explosives they name are added
// to c.explosives) and [simulation] (a deck firing after end_time is warned of).
void parse_explosives_and_holes(const TomlTable& top, Case& c);

// [delays] on the decks of the holes' groups (after parse_explosives_and_holes).
void apply_delay_groups(const TomlTable& top, Case& c);

// Materials that name an explosive must name a known one (after parse_explosives_and_holes);
// their density defaults to the explosive's.
void resolve_material_explosives(Case& c);

}  // namespace cdem
