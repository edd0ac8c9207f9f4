#include "cdem/io/case.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "cdem/core/error.hpp"
#include "cdem/core/input_file.hpp"
#include "cdem/io/case_sections.hpp"
#include "cdem/io/case_text.hpp"
#include "cdem/io/run_limits.hpp"
#include "cdem/io/toml_reader.hpp"

namespace cdem {

double release_angle_of(const Case& c) {
  return c.release_angle > 0 ? c.release_angle
                             : std::min(180.0, c.release_distance_factor * 180.0 / std::numbers::pi);
}

namespace {

namespace fs = std::filesystem;

// Apply "a.b.c=value" on top of the parsed document; numeric components index arrays.
void apply_override(toml::value& root, const std::string& ov, const std::string& file) {
  check_override_text(ov);
  const auto eq = ov.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(fmt::format("--set '{}': expected key=value (e.g. simulation.end_time=1e-3)", ov));
  const std::string key = ov.substr(0, eq), val = ov.substr(eq + 1);
  toml::value parsed;
  try {
    std::istringstream is("v = " + val);
    parsed = toml::parse(is, "--set " + key);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("--set '{}': the value is not valid TOML ({}): strings need "
                                 "quotes, e.g. key=\"text\"",
                                 ov, e.what()));
  }
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  toml::value* cur = &root;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const bool last = i + 1 == parts.size();
    const auto& p = parts[i];
    if (cur->is_array()) {
      // An index is digits only: std::stoul would take "-1" as 18446744073709551615.
      std::size_t idx = 0;
      const bool digits = !p.empty() && p.size() <= 9 &&
                          std::all_of(p.begin(), p.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
      if (!digits)
        throw InputError(fmt::format("--set '{}': '{}' is an array in {}; '{}' is not an index (0, "
                                     "1, 2, ...)",
                                     ov, parts[i - 1], file, p));
      idx = std::stoul(p);
      auto& arr = cur->as_array();
      if (idx >= arr.size())
        throw InputError(fmt::format("--set '{}': index {} out of range ({} has {} entries)", ov,
                                     idx, parts[i - 1], arr.size()));
      cur = &arr[idx];
    } else {
      if (!cur->is_table()) *cur = toml::table{};
      auto& t = cur->as_table();
      if (last) {
        t[p] = parsed.as_table().at("v");
        return;
      }
      if (!t.count(p)) t[p] = toml::table{};
      cur = &t[p];
    }
    if (last) {
      *cur = parsed.as_table().at("v");
      return;
    }
  }
}

Sym6 sym6(const TomlTable& t, const std::string& key) {
  const auto a = t.numbers(key);
  if (a.size() != 6 && a.size() != 4)
    throw InputError(fmt::format("{}: expected 6 numbers [xx, yy, zz, xy, yz, xz] (2D: 4 numbers "
                                 "[xx, yy, zz, xy]), got {}",
                                 t.where(key), a.size()));
  Sym6 s{};
  for (std::size_t i = 0; i < a.size(); ++i) s[i] = a[i];
  return s;
}

// Output times after end_time are dropped with a notice, not refused: a run shortened with
// --set simulation.end_time=... keeps the case's other output times.
void drop_late_output_times(const TomlTable& sim, Case& c) {
  std::string dropped;
  std::vector<double> kept;
  for (double t : c.output_times)
    if (t > c.end_time)
      dropped += fmt::format("{}{:g}", dropped.empty() ? "" : ", ", t);
    else
      kept.push_back(t);
  if (dropped.empty()) return;
  spdlog::warn("{}: output time(s) {} s after end_time = {:g} s dropped", sim.where("output_times"),
               dropped, c.end_time);
  c.output_times = std::move(kept);
}

}  // namespace

Case load_case(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw InputError(fmt::format("cannot open case file '{}': no such file", path));
  if (fs::is_directory(path, ec))
    throw InputError(fmt::format("cannot open case file '{}': it is a directory", path));
  const std::string text = read_input_file(path, "case file", kMaxCaseFileBytes);
  return parse_case(text, path, overrides);
}

Case parse_case(std::string_view text, const std::string& path,
                const std::vector<std::string>& overrides) {
  // The text is checked before toml11 sees it (case_text.hpp).
  check_case_text(text, path);
  toml::value root;
  try {
    std::istringstream is{std::string(text)};
    root = toml::parse(is, path);
  } catch (const toml::syntax_error& e) {
    throw InputError(fmt::format("{}: TOML syntax error:\n{}", path, e.what()));
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: cannot read: {}", path, e.what()));
  }
  for (const auto& ov : overrides) apply_override(root, ov, path);

  Case c;
  c.path = path;
  c.dir = fs::absolute(path).parent_path().string();
  const TomlTable top(root, path, "");
  top.check_known({"title", "mesh", "simulation", "material", "interface", "boundary",
                   "damping_zone", "monitor", "initial_stress", "explosive", "hole", "analysis",
                   "contact", "delays"});
  c.title = top.string("title", fs::path(path).stem().string());

  // ---- mesh (case_mesh.cpp) ----
  parse_mesh(top, c);

  // ---- simulation ----
  const auto sim = top.sub("simulation");
  if (!sim) throw InputError(fmt::format("{}: missing table [simulation] (at least end_time)", path));
  sim->check_known({"end_time", "dt_safety", "dt", "threads", "output_interval", "output_times",
                    "history_interval", "release_distance_factor", "release_angle", "energy_blowup_factor",
                    "contact_energy_limit", "interface_energy_limit", "max_steps", "gravity", "interfaces", "opened_stiffness", "mass_scaling_dt", "mass_scaling_limit",
                    "allow_large_run", "checkpoint_interval", "checkpoint_wall_interval"});
  c.end_time = sim->positive("end_time");
  c.dt_safety = sim->positive("dt_safety", 0.5);
  if (c.dt_safety > 1.0)
    throw InputError(fmt::format("{}: expected a value in (0, 1], got {} (above 1 the explicit "
                                 "scheme is unstable)",
                                 sim->where("dt_safety"), c.dt_safety));
  c.fixed_dt = sim->non_negative("dt", 0.0);
  {
    const std::int64_t threads = sim->integer("threads", 0);
    if (threads < 0 || threads > kMaxThreads)
      throw InputError(fmt::format("{}: expected an integer from 0 (all cores) to {}, got {}",
                                   sim->where("threads"), kMaxThreads, threads));
    c.threads = static_cast<int>(threads);
  }
  c.output_interval = sim->non_negative("output_interval", 0.0);
  if (sim->has("output_times")) c.output_times = sim->numbers("output_times");
  for (double t : c.output_times)
    if (t < 0)
      throw InputError(fmt::format("{}: {} is outside [0, end_time = {}]", sim->where("output_times"),
                                   t, c.end_time));
  drop_late_output_times(*sim, c);
  c.history_interval = sim->non_negative("history_interval", c.end_time / 200.0);
  c.release_distance_factor = sim->positive("release_distance_factor", 0.5);
  // (not given: 0, the release distance as a rotation, release_angle_of)
  c.release_angle = sim->has("release_angle") ? sim->positive("release_angle") : 0.0;
  if (c.release_angle > 180.0)
    throw InputError(fmt::format("{}: expected an angle in degrees in (0, 180] (180: a broken pair "
                                 "is released by distance only), got {}",
                                 sim->where("release_angle"), c.release_angle));
  c.energy_blowup_factor = sim->positive("energy_blowup_factor", 10.0);
  c.contact_energy_limit = sim->non_negative("contact_energy_limit", Case::kContactEnergyLimit);
  c.interface_energy_limit = sim->non_negative("interface_energy_limit", Case::kInterfaceEnergyLimit);
  c.max_steps = sim->integer("max_steps", 0);
  if (c.max_steps < 0)
    throw InputError(fmt::format("{}: expected an integer >= 0 (0: no limit), got {}", sim->where("max_steps"), c.max_steps));
  c.gravity = sim->vec("gravity", {});
  c.interface_mode = sim->choice("interfaces", {"tied", "springs"}, "tied") == "tied"
                     ? InterfaceMode::Tied
                     : InterfaceMode::Springs;
  c.opened_stiffness = sim->positive("opened_stiffness", 1.0);
  if (c.opened_stiffness > 4.0)
    throw InputError(fmt::format("{}: expected a value in (0, 4], got {} (the opened points' share "
                                 "of the blocks' stability limit; dt shrinks by 1 / sqrt(1 + it))",
                                 sim->where("opened_stiffness"), c.opened_stiffness));
  c.mass_scaling_dt = sim->non_negative("mass_scaling_dt", 0.0);
  c.mass_scaling_limit = sim->positive("mass_scaling_limit", 1e-4);
  if (c.mass_scaling_limit > 0.1)
    throw InputError(fmt::format("{}: expected a share of the model's mass in (0, 0.1], got {} (more "
                                 "added mass than that changes the blast's dynamics)",
                                 sim->where("mass_scaling_limit"), c.mass_scaling_limit));
  if (c.mass_scaling_dt > 0 && c.interface_mode != InterfaceMode::Tied)
    throw InputError(fmt::format("{}: mass scaling is available in the tied interface mode only "
                                 "(simulation.interfaces = \"tied\", the default)",
                                 sim->where("mass_scaling_dt")));
  if (c.mass_scaling_dt > 0 && c.fixed_dt > 0)
    throw InputError(fmt::format("{}: set either simulation.dt or simulation.mass_scaling_dt, not both",
                                 sim->where("mass_scaling_dt")));
  c.allow_large_run = sim->boolean("allow_large_run", false);
  c.checkpoint_interval = sim->non_negative("checkpoint_interval", 0.0);
  c.checkpoint_wall_interval = sim->non_negative("checkpoint_wall_interval", 600.0);
  if (norm(c.gravity) > 1e4)
    throw InputError(fmt::format("{}: |g| = {:g} m/s^2 is more than 1000 times the Earth's; "
                                 "expected m/s^2, e.g. [0, -9.81]",
                                 sim->where("gravity"), norm(c.gravity)));
  check_field_outputs(c);

  // ---- block and interface materials (case_materials.cpp) ----
  parse_materials(top, c);

  // ---- contact (SPEC 1.5): on by default wherever fracture is possible ----
  {
    bool can_break = false;
    for (const auto& im : c.interfaces)
      can_break = can_break || im.law != InterfaceLaw::Elastic || im.precracked;
    c.contact.enabled = can_break;
    if (const auto ct = top.sub("contact")) {
      ct->check_known({"enabled", "skin", "friction", "damping_ratio", "stiffness_factor", "candidates", "edges", "sleep", "passivity"});
      c.contact.enabled = ct->boolean("enabled", can_break);
      c.contact.skin = ct->non_negative("skin", 0.0);
      c.contact.friction = ct->has("friction") ? ct->non_negative("friction", 0.0) : -1.0;
      c.contact.damping_ratio = ct->non_negative("damping_ratio", 0.0);
      if (c.contact.damping_ratio > 1.0)
        throw InputError(fmt::format("{}: expected a damping ratio in [0, 1], got {}",
                                     ct->where("damping_ratio"), c.contact.damping_ratio));
      c.contact.stiffness_factor = ct->positive("stiffness_factor", 1.0);
      if (c.contact.stiffness_factor > 1.0)
        throw InputError(fmt::format("{}: expected a value in (0, 1], got {} (above 1 the contact "
                                     "stiffness would exceed the share of the stable step it is "
                                     "given)",
                                     ct->where("stiffness_factor"), c.contact.stiffness_factor));
      c.contact.cracked_faces = ct->choice("candidates", {"released", "cracked"}, "cracked") == "cracked";
      c.contact.edges = ct->boolean("edges", true);
      c.contact.sleep = ct->boolean("sleep", true);
      c.contact.passivity = ct->boolean("passivity", true);
    }
  }

  // ---- boundaries ----
  for (const auto& t : top.array_of_tables("boundary")) {
    t.check_known({"faces", "type", "velocity", "pressure", "table"});
    BoundaryCondition b;
    b.faces = t.string("faces");
    const std::string ty = t.choice("type", {"fixed", "roller", "non_reflecting", "velocity", "pressure"}, "");
    b.type = ty == "fixed" ? BoundaryType::Fixed
             : ty == "roller" ? BoundaryType::Roller
             : ty == "non_reflecting" ? BoundaryType::NonReflecting
             : ty == "velocity" ? BoundaryType::Velocity : BoundaryType::Pressure;
    if (b.type == BoundaryType::Velocity) {
      b.direction = t.vec("velocity");
      b.value = 1.0;
    }
    if (b.type == BoundaryType::Pressure) b.value = t.number("pressure");
    if (t.has("table")) b.table.points = t.table("table");
    c.boundaries.push_back(b);
  }

  for (const auto& t : top.array_of_tables("damping_zone")) {
    t.check_known({"region", "max_damping", "exponent"});
    DampingZone z;
    z.region = t.string("region");
    z.max_damping = t.positive("max_damping");
    z.exponent = t.positive("exponent", 2.0);
    c.damping_zones.push_back(z);
  }
  for (const auto& t : top.array_of_tables("monitor")) {
    t.check_known({"name", "point"});
    Monitor mo;
    mo.name = t.string("name");
    mo.point = t.vec("point");
    for (const auto& o : c.monitors)
      if (o.name == mo.name) throw InputError(fmt::format("{}: duplicate monitor name '{}'", t.where("name"), mo.name));
    c.monitors.push_back(mo);
  }
  // Each monitor is located by a search over the blocks and samples a row per history sample.
  if (c.monitors.size() > kMaxMonitors && !c.allow_large_run)
    throw InputError(fmt::format("{}: {} [[monitor]] entries, more than the {} allowed; set "
                                 "simulation.allow_large_run = true if they are meant",
                                 path, c.monitors.size(), kMaxMonitors));
  if (const auto is = top.sub("initial_stress")) {
    is->check_known({"stress", "gradient", "reference_level"});
    c.initial_stress.enabled = true;
    c.initial_stress.at_reference = sym6(*is, "stress");
    if (is->has("gradient")) c.initial_stress.gradient = sym6(*is, "gradient");
    c.initial_stress.reference_level = is->number("reference_level", 0.0);
  }
  // ---- explosives, holes and delays (case_charges.cpp) ----
  parse_explosives_and_holes(top, c);
  apply_delay_groups(top, c);
  if (const auto an = top.sub("analysis")) {
    an->check_known({"up", "surface_level", "damage_threshold", "main_faces"});
    c.analysis.up = an->vec("up", {});
    if (an->has("up") && norm(c.analysis.up) == 0)
      throw InputError(fmt::format("{}: a zero vector", an->where("up")));
    if (an->has("surface_level")) {
      c.analysis.surface_level = an->number("surface_level");
      c.analysis.surface_level_set = true;
    }
    c.analysis.damage_threshold = an->positive("damage_threshold", 1.0);
    if (c.analysis.damage_threshold > 1.0)
      throw InputError(fmt::format("{}: expected a value in (0, 1]", an->where("damage_threshold")));
    if (an->has("main_faces")) c.analysis.main_faces = an->strings("main_faces");
  }
  // Materials that name an explosive: a known one, whose density is theirs by default
  // (case_charges.cpp).
  resolve_material_explosives(c);
  return c;
}

ChargeSpec charge_spec(const Case& c) {
  ChargeSpec s;
  s.path = c.path;
  s.holes = c.holes;
  s.explosives = c.explosives;
  for (const auto& b : c.boundaries)
    if (b.type != BoundaryType::Pressure) s.closed_face_sets.push_back(b.faces);
  return s;
}

}  // namespace cdem
