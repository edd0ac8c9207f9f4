// A case file (TOML) parsed and validated into a Case before anything runs. Every error names
// the file, the key and what was expected (InputError). See docs/case_reference.md.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cdem/analysis/analysis_spec.hpp"
#include "cdem/analysis/monitor_spec.hpp"
#include "cdem/core/vec3.hpp"
#include "cdem/explosive/eos.hpp"
#include "cdem/explosive/gas_model.hpp"
#include "cdem/explosive/holes.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/model/boundary_spec.hpp"
#include "cdem/model/materials.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {

struct DampingZone {
  std::string region;       // the zone's region
  double max_damping = 0;   // mass-proportional coefficient at the outer edge (1/s)
  double exponent = 2.0;    // grading mu = mu_max (d / d_max)^exponent from the inner edge
};

struct InitialStress {
  bool enabled = false;
  Sym6 at_reference{};      // stress at the reference level (Pa, tension positive)
  Sym6 gradient{};          // d(sigma)/d(depth) (Pa/m); depth = reference_level - z (3D) or - y (2D)
  double reference_level = 0;
};

// How intact interfaces act (docs/theory.md "Tied interfaces"): "tied" (the nodes split from a
// vertex move as one while the points joining them are intact; springs only where the rock has
// broken) or "springs" (SPEC 1.3 as the method paper: every interface is a spring from t = 0).
enum class InterfaceMode { Tied, Springs };
inline const char* name_of(InterfaceMode i) { return i == InterfaceMode::Tied ? "tied" : "springs"; }

// A delay group's entry in [delays]: one delay for every deck of its holes, or one per deck
// from the bottom up (per_deck; every hole of the group then has that many decks).
struct DelayGroup {
  std::string name;
  std::vector<double> delays;  // s; one value, or one per deck
  bool per_deck = false;       // given as an array
};

struct Case {
  std::string path;         // the case file (for messages and relative paths)
  std::string dir;          // its directory
  std::string title;

  // [mesh]
  std::string mesh_file;    // absolute path, or empty when generated
  std::optional<GenerateSpec> generate;

  // [simulation]
  double end_time = 0;      // s
  double dt_safety = 0.5;
  double fixed_dt = 0;      // > 0: use this dt (must be below the stable one)
  int threads = 0;          // 0: all cores
  double output_interval = 0;           // field output (VTU) period, s (0: only the end)
  std::vector<double> output_times;     // explicit field output times (added to the period)
  double history_interval = 0;          // monitors, energy, fracture degree, s (default end_time/200; 0: every step)
  double release_distance_factor = 0.5; // broken pair released beyond this x block size
  // degrees; a broken pair whose faces have turned apart by more than this is released (180:
  // never); <= 0 (not given): release_distance_factor radians, at most 180 (release_angle_of)
  double release_angle = 0;
  double energy_blowup_factor = 10.0;   // stop when total energy > this x (input work + initial)
  static constexpr double kContactEnergyLimit = 0.02;
  double contact_energy_limit = kContactEnergyLimit;   // stop when contact has made more than this share of the
                                        // energy put in (its booked dissipation below -limit x it)
  static constexpr double kInterfaceEnergyLimit = 0.02;
  double interface_energy_limit = kInterfaceEnergyLimit;  // stop when the interfaces' booked dissipation has
                                        // fallen more than this share of the energy put in below its peak
  std::int64_t max_steps = 0;           // 0: unlimited
  InterfaceMode interface_mode = InterfaceMode::Tied;  // simulation.interfaces
  double opened_stiffness = 1.0;        // tied: opened points' share eta of the blocks' omega_max^2
  double mass_scaling_dt = 0;           // tied: > 0, blocks whose own stable step is below this step
                                        // get mass up to it (solver/time_step.hpp; 0: none, the paper's form)
  double mass_scaling_limit = 1e-4;     // the most mass that may be added, as a share of the model's
  bool allow_large_run = false;         // lifts the caps on steps, outputs, samples (run_limits.hpp)
  double checkpoint_interval = 0;       // s of simulated time between checkpoints (0: none)
  double checkpoint_wall_interval = 600;  // s of wall time between checkpoints (0: none)

  Vec3 gravity{};
  ContactSettings contact;              // [contact]
  std::vector<BlockMaterial> materials;
  std::vector<InterfaceMaterial> interfaces;
  std::vector<BoundaryCondition> boundaries;
  std::vector<DampingZone> damping_zones;
  std::vector<Monitor> monitors;
  InitialStress initial_stress;
  std::vector<ExplosiveDef> explosives;  // built-ins used by the case, then [[explosive]]
  std::vector<HoleDef> holes;
  std::vector<DelayGroup> delay_groups;  // [delays], in key order
  AnalysisSettings analysis;

  const ExplosiveDef* explosive(const std::string& name) const {
    for (const auto& e : explosives)
      if (e.name == name) return &e;
    return nullptr;
  }
};

// The release angle in effect (degrees): simulation.release_angle, or when not given the release
// distance as a rotation, release_distance_factor radians (a face turned by theta about the point
// moves its corners one block size away by ~theta x that size), at most 180.
double release_angle_of(const Case& c);

// Parse and validate. `overrides` are "dotted.key=value" strings applied on top of the file
// (the value is TOML: 3e-3, "text", [1, 2]). Throws InputError. The file must be a regular file
// of at most kMaxCaseFileBytes (input_file.hpp); its text is checked (case_text.hpp) before
// the TOML parser sees it.
Case load_case(const std::string& path, const std::vector<std::string>& overrides = {});

// The plain data the explosive models are built from (explosive/holes.hpp): the case's holes and
// explosives, and the face sets of its boundary conditions other than a pressure (the gas does
// not vent through them).
ChargeSpec charge_spec(const Case& c);

// load_case on text already read; `path` names it and places relative paths. No file is read.
Case parse_case(std::string_view text, const std::string& path,
                const std::vector<std::string>& overrides = {});

// Largest thread count a case or the command line may ask for (more than the machine has are
// used as the machine's processors, with a warning: run.cpp).
inline constexpr int kMaxThreads = 4096;

// The fully resolved case (every default filled in) as TOML text.
std::string resolved_case_toml(const Case& c);

}  // namespace cdem
