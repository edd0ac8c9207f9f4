#include "cdem/io/case.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cdem/core/error.hpp"
#include "cdem/core/input_file.hpp"
#include "cdem/explosive/explosive_library.hpp"
#include "cdem/io/case_text.hpp"
#include "cdem/io/run_limits.hpp"
#include "cdem/io/toml_reader.hpp"
#include "cdem/mesh/mesh_estimate.hpp"

namespace cdem {

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

std::string resolve_path(const std::string& dir, const std::string& p) {
  fs::path q(p);
  return q.is_absolute() ? q.string() : (fs::path(dir) / q).lexically_normal().string();
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

// Physical ranges of material constants. Outside the hard range a value is no density or
// modulus of any solid in SI units (and would overflow the time step: c_p = sqrt(M / rho));
// outside the usual range it is legal but looks like another unit (g/cm^3, MPa, GPa).
constexpr double kMinDensity = 1e-2, kMaxDensity = 1e6;          // kg/m^3, refused beyond
constexpr double kUsualDensity[2] = {500, 3e4};                  // kg/m^3, warned beyond
constexpr double kMinModulus = 1e3, kMaxModulus = 1e13;          // Pa, refused beyond
constexpr double kUsualModulus[2] = {1e6, 1.5e12};               // Pa, warned beyond
constexpr double kMaxStiffnessFactor = 1e4;

void check_density(const TomlTable& t, const std::string& key, double rho) {
  if (!(rho >= kMinDensity && rho <= kMaxDensity))
    throw InputError(fmt::format("{}: {:g} kg/m^3 is no density of a solid (expected {:g} to {:g} "
                                 "kg/m^3; rock is 1500-3500)",
                                 t.where(key), rho, kMinDensity, kMaxDensity));
  if (rho < kUsualDensity[0] || rho > kUsualDensity[1])
    spdlog::warn("{}: {:g} kg/m^3 is unusual (rock is 1500-3500 kg/m^3): is it in g/cm^3 or "
                 "another unit?",
                 t.where(key), rho);
}

void check_modulus(const TomlTable& t, const std::string& key, double e) {
  if (!(e >= kMinModulus && e <= kMaxModulus))
    throw InputError(fmt::format("{}: {:g} Pa is no Young's modulus of a solid (expected {:g} to "
                                 "{:g} Pa; rock is 1e9-1e11 Pa, i.e. 1-100 GPa)",
                                 t.where(key), e, kMinModulus, kMaxModulus));
  if (e < kUsualModulus[0] || e > kUsualModulus[1])
    spdlog::warn("{}: {:g} Pa is unusual for rock (1e9-1e11 Pa): is it in MPa or GPa?",
                 t.where(key), e);
}

// A 2D geometry (rectangle) takes [x, y]; a z would be dropped by the mesher.
void no_z_in_2d(const TomlTable& t, const std::string& key, double z) {
  if (z != 0)
    throw InputError(fmt::format("{}: z = {:g} for a rectangle (a 2D mesh in the plane z = 0); "
                                 "it would be dropped: give [x, y]",
                                 t.where(key), z));
}

// [[mesh.generate.refine]]: a ball around `point`, or with `to` a segment (a hole's axis).
RefineSpec parse_refine(const TomlTable& r) {
  r.check_known({"point", "to", "size", "radius", "grading"});
  RefineSpec rs;
  rs.point = r.vec("point");
  if (r.has("to")) {
    rs.to = r.vec("to");
    if (!(norm(*rs.to - rs.point) > 0))
      throw InputError(fmt::format("{}: the segment has zero length ('to' = 'point')", r.where("to")));
  }
  rs.size = r.positive("size");
  rs.radius = r.positive("radius");
  rs.grading = r.positive("grading", 0.0);
  return rs;
}

GenerateSpec parse_generate(const TomlTable& g) {
  g.check_known({"shape", "origin", "size", "element_size", "quads", "hole", "refine", "ring_width",
                 "ring_element_size", "region", "circle_segments", "wall_sizing"});
  GenerateSpec s;
  s.shape = g.choice("shape", {"rectangle", "box", "cylinder"}, "");
  s.origin = g.vec("origin", {});
  s.size = g.vec("size");
  const int need = s.shape == "rectangle" ? 2 : 3;
  if (need == 2) {
    no_z_in_2d(g, "origin", s.origin.z);
    no_z_in_2d(g, "size", s.size.z);
  }
  if (s.shape == "cylinder") {
    if (!(s.size.x > 0 && s.size.z > 0))
      throw InputError(fmt::format("{}: a cylinder needs size = [radius, 0, height], both > 0",
                                   g.where("size")));
  } else {
    if (!(s.size.x > 0 && s.size.y > 0 && (need == 2 || s.size.z > 0)))
      throw InputError(fmt::format("{}: expected {} positive lengths", g.where("size"), need));
  }
  s.element_size = g.positive("element_size");
  s.quads = g.boolean("quads", false);
  {
    const auto n = g.integer("circle_segments", 16);
    if (n < 0 || n > 1000)
      throw InputError(fmt::format("{}: expected an integer from 0 to 1000 (elements per full turn "
                                   "of a curved wall; 0: no curvature sizing), got {}",
                                   g.where("circle_segments"), n));
    s.circle_segments = static_cast<int>(n);
  }
  s.region = g.string("region", "rock");
  s.wall_sizing = g.choice("wall_sizing", {"finest", "refine"}, "finest");
  s.ring_width = g.non_negative("ring_width", 0.0);
  s.ring_element_size = g.positive("ring_element_size", s.element_size);
  for (const auto& h : g.array_of_tables("hole")) {
    h.check_known({"center", "radius", "axis", "depth", "region"});
    HoleSpec hs;
    hs.center = h.vec("center");
    hs.radius = h.positive("radius");
    hs.axis = h.vec("axis", need == 2 ? Vec3{0, -1, 0} : Vec3{0, 0, -1});
    if (need == 2) {
      no_z_in_2d(h, "center", hs.center.z);
      no_z_in_2d(h, "axis", hs.axis.z);
    }
    if (norm(hs.axis) == 0) throw InputError(fmt::format("{}: the axis is a zero vector", h.where("axis")));
    hs.axis = normalized(hs.axis);
    hs.depth = h.non_negative("depth", 0.0);
    hs.region = h.string("region", "");
    s.holes.push_back(hs);
  }
  for (const auto& r : g.array_of_tables("refine")) {
    RefineSpec rs = parse_refine(r);
    if (need == 2) {
      no_z_in_2d(r, "point", rs.point.z);
      if (rs.to) no_z_in_2d(r, "to", rs.to->z);
    }
    s.refine.push_back(rs);
  }
  return s;
}

std::string builtin_list() {
  std::string s;
  for (const auto& n : builtin_explosive_names()) s += (s.empty() ? "'" : ", '") + n + "'";
  return s;
}

void parse_explosives_and_holes(const TomlTable& top, Case& c) {
  for (const auto& t : top.array_of_tables("explosive")) {
    t.check_known({"name", "eos", "density", "detonation_velocity", "detonation_heat", "gamma1",
                   "gamma2", "A", "B", "R1", "R2", "omega", "E0"});
    ExplosiveDef e;
    e.name = t.string("name");
    if (t.has("density")) check_density(t, "density", t.positive("density"));
    const std::string where = fmt::format("{}: explosive '{}'", t.file(), e.name);
    const std::string kind = t.choice("eos", {"landau", "jwl"}, "landau");
    if (kind == "landau")
      e.eos = LandauEos::make(t.positive("density"), t.positive("detonation_velocity"),
                              t.positive("detonation_heat"), t.number("gamma1", 3.0),
                              t.number("gamma2", 4.0 / 3.0), where);
    else
      e.eos = JwlEos::make(t.positive("density"), t.positive("detonation_velocity"), t.positive("A"),
                           t.positive("B"), t.positive("R1"), t.positive("R2"), t.positive("omega"),
                           t.positive("E0"), where);
    if (c.explosive(e.name))
      throw InputError(fmt::format("{}: duplicate explosive name '{}'", t.where("name"), e.name));
    c.explosives.push_back(e);
  }
  auto resolve = [&](const std::string& name, const std::string& where) {
    if (c.explosive(name)) return;
    const auto b = builtin_explosive(name);
    if (!b)
      throw InputError(fmt::format("{}: unknown explosive '{}' (built-in: {}; or define it in "
                                   "[[explosive]])",
                                   where, name, builtin_list()));
    c.explosives.push_back({name, *b});
  };
  for (const auto& m : c.materials)
    if (!m.explosive.empty() && !c.explosive(m.explosive) && builtin_explosive(m.explosive))
      c.explosives.push_back({m.explosive, *builtin_explosive(m.explosive)});

  for (const auto& t : top.array_of_tables("hole")) {
    t.check_known({"name", "group", "collar", "end", "direction", "depth", "diameter", "model",
                   "attenuation_exponent", "attenuation_length", "cavity", "charge", "gas",
                   "stemming_density", "stemming_shear_strength", "vent_coefficient"});
    HoleDef h;
    h.name = t.string("name");
    h.group = t.string("group", "");
    if (h.group.find('.') != std::string::npos)
      throw InputError(fmt::format("{}: '{}': a group name cannot contain '.' (it is a key of "
                                   "[delays], and --set splits keys at dots)",
                                   t.where("group"), h.group));
    h.collar = t.vec("collar");
    if (t.has("end") == t.has("depth"))
      throw InputError(fmt::format("{}: a hole needs either 'end' (the bottom point) or "
                                   "'direction' and 'depth'",
                                   t.where("end")));
    if (t.has("end")) {
      h.end = t.vec("end");
    } else {
      const Vec3 d = t.vec("direction");
      if (norm(d) == 0) throw InputError(fmt::format("{}: a zero vector", t.where("direction")));
      h.end = h.collar + t.positive("depth") * normalized(d);
    }
    if (!(h.length() > 0))
      throw InputError(fmt::format("{}: the hole has zero length (collar = end)", t.where("end")));
    h.diameter = t.positive("diameter");
    if (h.diameter > 2.0 || h.diameter < 5e-3)
      spdlog::warn("{}: {:g} m is an unusual blasthole diameter (25 mm to 0.5 m are usual): is it "
                   "in another unit than metres?",
                   t.where("diameter"), h.diameter);
    h.model = t.choice("model", {"bar", "solid"}, "bar") == "bar" ? ChargeModel::Bar : ChargeModel::Solid;
    h.attenuation_exponent = t.non_negative("attenuation_exponent", 1.25);
    h.cavity = t.boolean("cavity", true);
    {
      const std::string g = t.choice("gas", {"literal", "cavity", "cracks"}, "cracks");
      h.gas = g == "literal" ? GasModel::Literal : (g == "cavity" ? GasModel::Cavity : GasModel::Cracks);
    }
    h.stemming_density = t.positive("stemming_density", 2000.0);
    h.stemming_shear_strength = t.non_negative("stemming_shear_strength", 1e6);
    h.vent_coefficient = t.positive("vent_coefficient", 1.0);
    if (h.vent_coefficient > 1.0)
      throw InputError(fmt::format("{}: expected a discharge coefficient in (0, 1], got {}",
                                   t.where("vent_coefficient"), h.vent_coefficient));
    h.lc_element_size =
        t.choice("attenuation_length", {"equivalent_radius", "element_size"}, "equivalent_radius") ==
        "element_size";
    const Vec3 up = normalized(h.collar - h.end);
    double s = 0;  // distance from the bottom
    for (const auto& q : t.array_of_tables("charge")) {
      q.check_known({"stemming", "explosive", "length", "delay", "initiation"});
      if (q.has("stemming")) {
        if (q.has("explosive"))
          throw InputError(fmt::format("{}: a charge entry is either stemming or a deck, not both",
                                       q.where("stemming")));
        const double l = q.positive("stemming");
        h.stemming.emplace_back(s, s + l);
        s += l;
        continue;
      }
      Deck d;
      d.explosive = q.string("explosive");
      resolve(d.explosive, q.where("explosive"));
      d.length = q.positive("length");
      d.own_delay = q.non_negative("delay", 0.0);
      d.delay = d.own_delay;  // plus the group's delay (apply_delay_groups)
      if (d.own_delay >= c.end_time)
        spdlog::warn("{}: the deck of hole '{}' fires at {:g} s, at or after end_time = {:g} s: it "
                     "never fires in this run",
                     q.where("delay"), h.name, d.own_delay, c.end_time);
      d.initiate_top = q.choice("initiation", {"bottom", "top"}, "bottom") == "top";
      d.bottom = h.end + s * up;
      d.top = h.end + (s + d.length) * up;
      s += d.length;
      h.decks.push_back(d);
    }
    if (h.decks.empty())
      throw InputError(fmt::format("{}: hole '{}' has no charge: add [[hole.charge]] entries "
                                   "(explosive, length) from the bottom up",
                                   t.where("charge"), h.name));
    if (s > h.length() * (1 + 1e-9))
      throw InputError(fmt::format("{}: the charges and stemming of hole '{}' add up to {:.6g} m, "
                                   "longer than the hole ({:.6g} m)",
                                   t.where("charge"), h.name, s, h.length()));
    if (s < h.length()) h.stemming.emplace_back(s, h.length());  // top stemming (not modelled)
    for (const auto& o : c.holes) {
      if (o.name == h.name) throw InputError(fmt::format("{}: duplicate hole name '{}'", t.where("name"), h.name));
      // Two holes in one place (both ends within the larger radius, either way round) put two
      // charges into the same rock: a copy-and-paste mistake.
      const double tol = 0.5 * std::max(o.diameter, h.diameter);
      const bool same = (norm(o.collar - h.collar) <= tol && norm(o.end - h.end) <= tol) ||
                        (norm(o.collar - h.end) <= tol && norm(o.end - h.collar) <= tol);
      if (same)
        throw InputError(fmt::format("{}: hole '{}' lies on hole '{}' (collars {:.3g} m apart, "
                                     "bottoms {:.3g} m apart, within the radius {:.3g} m): two "
                                     "charges in one hole",
                                     t.where("collar"), h.name, o.name, norm(o.collar - h.collar),
                                     norm(o.end - h.end), tol));
    }
    c.holes.push_back(h);
  }
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

// [delays]: "group" = delay (s) for every deck of the group's holes, or "group" = [d1, d2, ...]
// one per deck from the bottom up. A deck fires at its group's delay plus its own `delay`.
// Keys are the names of [[hole]] groups (an unknown one is an error, a typo would otherwise
// fire nothing), so `--set delays.2=0.02` retimes group "2" in one override.
void apply_delay_groups(const TomlTable& top, Case& c) {
  const auto dl = top.sub("delays");
  if (!dl) return;
  std::vector<std::string> groups;
  for (const auto& h : c.holes)
    if (!h.group.empty() && std::find(groups.begin(), groups.end(), h.group) == groups.end())
      groups.push_back(h.group);
  std::string list;
  for (const auto& g : groups) list += (list.empty() ? "'" : ", '") + g + "'";
  for (const auto& [key, val] : top.raw("delays")->as_table()) {
    DelayGroup g;
    g.name = key;
    if (val.is_array()) {
      g.per_deck = true;
      g.delays = dl->numbers(key);
      if (g.delays.empty())
        throw InputError(fmt::format("{}: an empty array (give one delay, or one per deck from "
                                     "the bottom up)",
                                     dl->where(key)));
    } else {
      g.delays = {dl->number(key)};
    }
    for (double d : g.delays)
      if (!(d >= 0))
        throw InputError(fmt::format("{}: expected delays >= 0 (s), got {}", dl->where(key), d));
    if (std::find(groups.begin(), groups.end(), key) == groups.end())
      throw InputError(fmt::format("{}: no [[hole]] has group = \"{}\" (the holes' groups: {})",
                                   dl->where(key), key, list.empty() ? "none" : list));
    for (auto& h : c.holes) {
      if (h.group != key) continue;
      if (g.per_deck && g.delays.size() != h.decks.size())
        throw InputError(fmt::format("{}: {} delays (one per deck) but hole '{}' of group '{}' has "
                                     "{} deck(s)",
                                     dl->where(key), g.delays.size(), h.name, key, h.decks.size()));
      for (std::size_t k = 0; k < h.decks.size(); ++k)
        h.decks[k].delay = h.decks[k].own_delay + g.delays[g.per_deck ? k : 0];
    }
    c.delay_groups.push_back(g);
  }
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

  // ---- mesh ----
  const auto mesh = top.sub("mesh");
  if (!mesh) throw InputError(fmt::format("{}: missing table [mesh] (give 'file' or [mesh.generate])", path));
  mesh->check_known({"file", "generate"});
  if (mesh->has("file") == mesh->has("generate"))
    throw InputError(fmt::format("{}: [mesh] needs exactly one of 'file' (a Gmsh .msh) or "
                                 "[mesh.generate]",
                                 path));
  if (mesh->has("file")) {
    c.mesh_file = resolve_path(c.dir, mesh->string("file"));
  } else {
    c.generate = parse_generate(*mesh->sub("generate"));
    // Sized now, naming the key, before anything is meshed (generate_mesh checks again).
    const MeshEstimate est = estimate_generated_mesh(*c.generate);
    const std::string why = model_size_problem(
        est.elements, c.generate->shape == "rectangle" ? 2 : 3, "mostly from " + est.largest);
    if (!why.empty())
      throw InputError(
          fmt::format("{}: key 'mesh.generate.{}': {}", path, est.largest_key, why));
  }

  // ---- simulation ----
  const auto sim = top.sub("simulation");
  if (!sim) throw InputError(fmt::format("{}: missing table [simulation] (at least end_time)", path));
  sim->check_known({"end_time", "dt_safety", "dt", "threads", "output_interval", "output_times",
                    "history_interval", "release_distance_factor", "energy_blowup_factor",
                    "max_steps", "gravity", "interfaces", "opened_stiffness",
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
  c.energy_blowup_factor = sim->positive("energy_blowup_factor", 10.0);
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
  c.allow_large_run = sim->boolean("allow_large_run", false);
  c.checkpoint_interval = sim->non_negative("checkpoint_interval", 0.0);
  c.checkpoint_wall_interval = sim->non_negative("checkpoint_wall_interval", 600.0);
  if (norm(c.gravity) > 1e4)
    throw InputError(fmt::format("{}: |g| = {:g} m/s^2 is more than 1000 times the Earth's; "
                                 "expected m/s^2, e.g. [0, -9.81]",
                                 sim->where("gravity"), norm(c.gravity)));
  check_field_outputs(c);

  // ---- block materials ----
  const auto mats = top.array_of_tables("material");
  if (mats.empty())
    throw InputError(fmt::format("{}: no [[material]]: at least one is needed (density, "
                                 "youngs_modulus, poisson_ratio, regions)",
                                 path));
  for (const auto& t : mats) {
    t.check_known({"name", "regions", "density", "youngs_modulus", "poisson_ratio", "damping",
                   "local_damping", "explosive"});
    BlockMaterial m;
    m.name = t.string("name");
    m.regions = t.strings("regions");
    if (m.regions.empty()) throw InputError(fmt::format("{}: lists no region", t.where("regions")));
    m.explosive = t.string("explosive", "");
    // An explosive region's density defaults to the explosive's (filled in below).
    m.density = m.explosive.empty() ? t.positive("density") : t.positive("density", -1.0);
    m.youngs = m.explosive.empty() ? t.positive("youngs_modulus") : t.positive("youngs_modulus", 1e9);
    if (m.explosive.empty() && !t.has("poisson_ratio")) t.fail("poisson_ratio", "a number in (-1, 0.5)");
    m.poisson = t.number("poisson_ratio", 0.25);
    if (!(m.poisson > -1.0 && m.poisson < 0.5))
      throw InputError(fmt::format("{}: expected a Poisson ratio in (-1, 0.5), got {}",
                                   t.where("poisson_ratio"), m.poisson));
    if (m.explosive.empty() || t.has("density")) check_density(t, "density", m.density);
    if (m.explosive.empty() || t.has("youngs_modulus")) check_modulus(t, "youngs_modulus", m.youngs);
    m.damping = t.non_negative("damping", 0.0);
    m.local_damping = t.non_negative("local_damping", 0.0);
    if (m.local_damping >= 1.0)
      throw InputError(fmt::format("{}: expected a value in [0, 1)", t.where("local_damping")));
    for (const auto& o : c.materials)
      if (o.name == m.name) throw InputError(fmt::format("{}: duplicate material name '{}'", t.where("name"), m.name));
    c.materials.push_back(m);
  }

  // ---- interface materials ----
  for (const auto& t : top.array_of_tables("interface")) {
    t.check_known({"name", "pairs", "default", "law", "tensile_strength", "cohesion",
                   "friction_angle", "residual_friction_angle", "dilation_angle",
                   "tensile_fracture_energy", "shear_fracture_energy", "stiffness_factor",
                   "precracked"});
    InterfaceMaterial im;
    im.name = t.string("name");
    const std::string law = t.choice("law", {"mohr_coulomb", "fracture_energy", "elastic"}, "mohr_coulomb");
    im.law = law == "mohr_coulomb" ? InterfaceLaw::MohrCoulomb
             : law == "fracture_energy" ? InterfaceLaw::FractureEnergy : InterfaceLaw::Elastic;
    if (im.law != InterfaceLaw::Elastic) {
      if (!t.has("tensile_strength")) t.fail("tensile_strength", "a number >= 0 (Pa)");
      im.tensile_strength = t.non_negative("tensile_strength", 0.0);
      if (!t.has("cohesion")) t.fail("cohesion", "a number >= 0 (Pa)");
      im.cohesion = t.non_negative("cohesion", 0.0);
    }
    im.friction_deg = t.number("friction_angle", 0.0);
    im.residual_friction_deg = t.number("residual_friction_angle", -1.0);
    im.dilation_deg = t.number("dilation_angle", 0.0);
    for (const char* k : {"friction_angle", "dilation_angle", "residual_friction_angle"})
      if (t.has(k) && (t.number(k) < 0 || t.number(k) >= 90))
        throw InputError(fmt::format("{}: expected an angle in degrees in [0, 90), got {}", t.where(k),
                                     t.number(k)));
    if (im.law == InterfaceLaw::FractureEnergy) {
      im.gt = t.positive("tensile_fracture_energy");
      im.gs = t.positive("shear_fracture_energy");
    }
    im.stiffness_factor = t.positive("stiffness_factor", 10.0);
    if (im.stiffness_factor > kMaxStiffnessFactor)
      throw InputError(fmt::format("{}: {:g} is beyond {:g} (k_n = alpha E / h; alpha = 100 already "
                                   "makes dt 3 times smaller)",
                                   t.where("stiffness_factor"), im.stiffness_factor,
                                   kMaxStiffnessFactor));
    im.precracked = t.boolean("precracked", false);
    im.is_default = t.boolean("default", false);
    if (t.has("pairs")) {
      const toml::value* r = t.raw("pairs");
      if (!r->is_array()) t.fail("pairs", "an array of [region, region] pairs");
      for (const auto& e : r->as_array()) {
        if (!e.is_array() || e.as_array().size() != 2 || !e.as_array()[0].is_string() ||
            !e.as_array()[1].is_string())
          throw InputError(fmt::format("{}: expected pairs like [[\"rock\", \"rock\"]]", t.where("pairs")));
        im.pairs.emplace_back(e.as_array()[0].as_string().str, e.as_array()[1].as_string().str);
      }
    }
    c.interfaces.push_back(im);
  }

  // ---- contact (SPEC 1.5): on by default wherever fracture is possible ----
  {
    bool can_break = false;
    for (const auto& im : c.interfaces)
      can_break = can_break || im.law != InterfaceLaw::Elastic || im.precracked;
    c.contact.enabled = can_break;
    if (const auto ct = top.sub("contact")) {
      ct->check_known({"enabled", "skin", "friction", "damping_ratio", "stiffness_factor"});
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
  // Materials that name an explosive must name a known one; their density defaults to it.
  for (auto& m : c.materials)
    if (!m.explosive.empty() && !c.explosive(m.explosive))
      throw InputError(fmt::format("{}: material '{}': unknown explosive '{}' (built-in: {}; or "
                                   "define it in [[explosive]])",
                                   path, m.name, m.explosive, builtin_list()));
    else if (!m.explosive.empty() && m.density < 0)
      m.density = explosive_density(c.explosive(m.explosive)->eos);
  return c;
}

namespace {
std::string vec_str(Vec3 v) { return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", v.x, v.y, v.z); }
std::string q(const std::string& s) {
  std::string o = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\';
    o += ch;
  }
  return o + "\"";
}
std::string sym_str(const Sym6& s) {
  return fmt::format("[{:.17g}, {:.17g}, {:.17g}, {:.17g}, {:.17g}, {:.17g}]", s[0], s[1], s[2], s[3], s[4], s[5]);
}
std::string table_str(const TimeTable& t) {
  std::string o = "[";
  for (const auto& p : t.points) o += fmt::format("{}[{:.17g}, {:.17g}]", o.size() > 1 ? ", " : "", p.first, p.second);
  return o + "]";
}
}  // namespace

std::string resolved_case_toml(const Case& c) {
  std::string o;
  o += fmt::format("# Fully resolved case: every default filled in. Run it again with\n"
                   "#   cdemblast run <this file>\n# Source: {}\n\n", c.path);
  o += fmt::format("title = {}\n\n[mesh]\n", q(c.title));
  if (!c.mesh_file.empty()) {
    o += fmt::format("file = {}\n", q(c.mesh_file));
  } else {
    const auto& g = *c.generate;
    o += fmt::format("[mesh.generate]\nshape = {}\norigin = {}\nsize = {}\nelement_size = {:.17g}\n"
                     "quads = {}\nregion = {}\nring_width = {:.17g}\nring_element_size = {:.17g}\n"
                     "circle_segments = {}\nwall_sizing = {}\n",
                     q(g.shape), vec_str(g.origin), vec_str(g.size), g.element_size, g.quads,
                     q(g.region), g.ring_width, g.ring_element_size, g.circle_segments,
                     q(g.wall_sizing));
    for (const auto& h : g.holes)
      o += fmt::format("[[mesh.generate.hole]]\ncenter = {}\nradius = {:.17g}\naxis = {}\n"
                       "depth = {:.17g}\nregion = {}\n",
                       vec_str(h.center), h.radius, vec_str(h.axis), h.depth, q(h.region));
    for (const auto& r : g.refine) {
      o += fmt::format("[[mesh.generate.refine]]\npoint = {}\nsize = {:.17g}\nradius = {:.17g}\n",
                       vec_str(r.point), r.size, r.radius);
      if (r.to) o += fmt::format("to = {}\n", vec_str(*r.to));
      if (r.grading > 0) o += fmt::format("grading = {:.17g}\n", r.grading);
    }
  }
  o += fmt::format("\n[simulation]\nend_time = {:.17g}\ndt_safety = {:.17g}\ndt = {:.17g}\n"
                   "threads = {}\noutput_interval = {:.17g}\nhistory_interval = {:.17g}\n"
                   "release_distance_factor = {:.17g}\nenergy_blowup_factor = {:.17g}\n"
                   "max_steps = {}\ngravity = {}\ninterfaces = {}\nopened_stiffness = {:.17g}\n"
                   "allow_large_run = {}\ncheckpoint_interval = {:.17g}\n"
                   "checkpoint_wall_interval = {:.17g}\n",
                   c.end_time, c.dt_safety, c.fixed_dt, c.threads, c.output_interval,
                   c.history_interval, c.release_distance_factor, c.energy_blowup_factor,
                   c.max_steps, vec_str(c.gravity), q(name_of(c.interface_mode)), c.opened_stiffness,
                   c.allow_large_run, c.checkpoint_interval, c.checkpoint_wall_interval);
  o += "output_times = [";
  for (std::size_t i = 0; i < c.output_times.size(); ++i)
    o += fmt::format("{}{:.17g}", i ? ", " : "", c.output_times[i]);
  o += "]\n";
  o += fmt::format("\n[contact]\nenabled = {}\nskin = {:.17g}\ndamping_ratio = {:.17g}\n"
                   "stiffness_factor = {:.17g}\n",
                   c.contact.enabled ? "true" : "false", c.contact.skin, c.contact.damping_ratio,
                   c.contact.stiffness_factor);
  if (c.contact.friction >= 0) o += fmt::format("friction = {:.17g}\n", c.contact.friction);
  for (const auto& m : c.materials) {
    o += fmt::format("\n[[material]]\nname = {}\nregions = [", q(m.name));
    for (std::size_t i = 0; i < m.regions.size(); ++i) o += (i ? ", " : "") + q(m.regions[i]);
    o += fmt::format("]\ndensity = {:.17g}\nyoungs_modulus = {:.17g}\npoisson_ratio = {:.17g}\n"
                     "damping = {:.17g}\nlocal_damping = {:.17g}\n",
                     m.density, m.youngs, m.poisson, m.damping, m.local_damping);
    if (!m.explosive.empty()) o += fmt::format("explosive = {}\n", q(m.explosive));
  }
  for (const auto& im : c.interfaces) {
    o += fmt::format("\n[[interface]]\nname = {}\nlaw = {}\ndefault = {}\npairs = [", q(im.name),
                     q(name_of(im.law)), im.is_default);
    for (std::size_t i = 0; i < im.pairs.size(); ++i)
      o += fmt::format("{}[{}, {}]", i ? ", " : "", q(im.pairs[i].first), q(im.pairs[i].second));
    o += fmt::format("]\ntensile_strength = {:.17g}\ncohesion = {:.17g}\nfriction_angle = {:.17g}\n"
                     "residual_friction_angle = {:.17g}\ndilation_angle = {:.17g}\n"
                     "stiffness_factor = {:.17g}\nprecracked = {}\n",
                     im.tensile_strength, im.cohesion, im.friction_deg, im.residual_friction(),
                     im.dilation_deg, im.stiffness_factor, im.precracked);
    if (im.law == InterfaceLaw::FractureEnergy)
      o += fmt::format("tensile_fracture_energy = {:.17g}\nshear_fracture_energy = {:.17g}\n", im.gt, im.gs);
  }
  for (const auto& b : c.boundaries) {
    o += fmt::format("\n[[boundary]]\nfaces = {}\ntype = {}\n", q(b.faces), q(name_of(b.type)));
    if (b.type == BoundaryType::Velocity) o += fmt::format("velocity = {}\n", vec_str(b.direction));
    if (b.type == BoundaryType::Pressure) o += fmt::format("pressure = {:.17g}\n", b.value);
    o += fmt::format("table = {}\n", table_str(b.table));
  }
  for (const auto& z : c.damping_zones)
    o += fmt::format("\n[[damping_zone]]\nregion = {}\nmax_damping = {:.17g}\nexponent = {:.17g}\n",
                     q(z.region), z.max_damping, z.exponent);
  for (const auto& mo : c.monitors)
    o += fmt::format("\n[[monitor]]\nname = {}\npoint = {}\n", q(mo.name), vec_str(mo.point));
  for (const auto& e : c.explosives) {
    o += fmt::format("\n[[explosive]]\nname = {}\neos = {}\n", q(e.name), q(std::string(eos_kind(e.eos))));
    if (const auto* l = std::get_if<LandauEos>(&e.eos))
      o += fmt::format("density = {:.17g}\ndetonation_velocity = {:.17g}\ndetonation_heat = {:.17g}\n"
                       "gamma1 = {:.17g}\ngamma2 = {:.17g}\n",
                       l->rho_w, l->D, l->Q_w, l->gamma1, l->gamma2);
    else if (const auto* j = std::get_if<JwlEos>(&e.eos))
      o += fmt::format("density = {:.17g}\ndetonation_velocity = {:.17g}\nA = {:.17g}\nB = {:.17g}\n"
                       "R1 = {:.17g}\nR2 = {:.17g}\nomega = {:.17g}\nE0 = {:.17g}\n",
                       j->rho0, j->D, j->A, j->B, j->R1, j->R2, j->omega, j->E0);
  }
  for (const auto& h : c.holes) {
    o += fmt::format("\n[[hole]]\nname = {}\ncollar = {}\nend = {}\ndiameter = {:.17g}\nmodel = {}\n"
                     "attenuation_exponent = {:.17g}\nattenuation_length = {}\ncavity = {}\n"
                     "gas = {}\nstemming_density = {:.17g}\nstemming_shear_strength = {:.17g}\n"
                     "vent_coefficient = {:.17g}\n",
                     q(h.name), vec_str(h.collar), vec_str(h.end), h.diameter,
                     q(h.model == ChargeModel::Bar ? "bar" : "solid"), h.attenuation_exponent,
                     q(h.lc_element_size ? "element_size" : "equivalent_radius"), h.cavity,
                     q(name_of(h.gas)), h.stemming_density, h.stemming_shear_strength,
                     h.vent_coefficient);
    if (!h.group.empty()) o += fmt::format("group = {}\n", q(h.group));
    // Charges from the bottom up, stemming between them.
    std::vector<std::pair<double, std::string>> items;
    const Vec3 up = normalized(h.collar - h.end);
    for (const auto& s : h.stemming)
      if (s.second < h.length() - 1e-12 || s.first == 0)
        items.emplace_back(s.first, fmt::format("[[hole.charge]]\nstemming = {:.17g}\n", s.second - s.first));
    for (const auto& d : h.decks)
      items.emplace_back(dot(d.bottom - h.end, up),
                         fmt::format("[[hole.charge]]\nexplosive = {}\nlength = {:.17g}\ndelay = {:.17g}\n"
                                     "initiation = {}\n",
                                     q(d.explosive), d.length, d.own_delay, q(d.initiate_top ? "top" : "bottom")));
    std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& it : items) o += it.second;
  }
  o += fmt::format("\n[analysis]\ndamage_threshold = {:.17g}\n", c.analysis.damage_threshold);
  if (norm(c.analysis.up) > 0) o += fmt::format("up = {}\n", vec_str(c.analysis.up));
  if (c.analysis.surface_level_set) o += fmt::format("surface_level = {:.17g}\n", c.analysis.surface_level);
  if (!c.analysis.main_faces.empty()) {
    o += "main_faces = [";
    for (std::size_t i = 0; i < c.analysis.main_faces.size(); ++i) o += (i ? ", " : "") + q(c.analysis.main_faces[i]);
    o += "]\n";
  }
  if (!c.delay_groups.empty()) {
    o += "\n[delays]\n";
    for (const auto& g : c.delay_groups) {
      std::string v;
      for (std::size_t k = 0; k < g.delays.size(); ++k) v += fmt::format("{}{:.17g}", k ? ", " : "", g.delays[k]);
      o += fmt::format("{} = {}\n", q(g.name), g.per_deck ? "[" + v + "]" : v);
    }
  }
  if (c.initial_stress.enabled)
    o += fmt::format("\n[initial_stress]\nstress = {}\ngradient = {}\nreference_level = {:.17g}\n",
                     sym_str(c.initial_stress.at_reference), sym_str(c.initial_stress.gradient),
                     c.initial_stress.reference_level);
  return o;
}

}  // namespace cdem
