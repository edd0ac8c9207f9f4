#include "cdem/io/case.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>
#include <variant>

namespace cdem {

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
                   "release_distance_factor = {:.17g}\nrelease_angle = {:.17g}\nenergy_blowup_factor = {:.17g}\n"
                   "max_steps = {}\ngravity = {}\ninterfaces = {}\nopened_stiffness = {:.17g}\n"
                   "allow_large_run = {}\ncheckpoint_interval = {:.17g}\n"
                   "checkpoint_wall_interval = {:.17g}\n",
                   c.end_time, c.dt_safety, c.fixed_dt, c.threads, c.output_interval,
                   c.history_interval, c.release_distance_factor, release_angle_of(c), c.energy_blowup_factor,
                   c.max_steps, vec_str(c.gravity), q(name_of(c.interface_mode)), c.opened_stiffness,
                   c.allow_large_run, c.checkpoint_interval, c.checkpoint_wall_interval);
  // (only when set: checkpoints of cases resolved before the key existed still match)
  if (c.contact_energy_limit != Case::kContactEnergyLimit) o += fmt::format("contact_energy_limit = {:.17g}\n", c.contact_energy_limit);
  if (c.interface_energy_limit != Case::kInterfaceEnergyLimit)
    o += fmt::format("interface_energy_limit = {:.17g}\n", c.interface_energy_limit);
  if (c.mass_scaling_dt > 0)
    o += fmt::format("mass_scaling_dt = {:.17g}\nmass_scaling_limit = {:.17g}\n", c.mass_scaling_dt,
                     c.mass_scaling_limit);
  o += "output_times = [";
  for (std::size_t i = 0; i < c.output_times.size(); ++i)
    o += fmt::format("{}{:.17g}", i ? ", " : "", c.output_times[i]);
  o += "]\n";
  o += fmt::format("\n[contact]\nenabled = {}\nskin = {:.17g}\ndamping_ratio = {:.17g}\n"
                   "stiffness_factor = {:.17g}\n",
                   c.contact.enabled ? "true" : "false", c.contact.skin, c.contact.damping_ratio,
                   c.contact.stiffness_factor);
  if (c.contact.friction >= 0) o += fmt::format("friction = {:.17g}\n", c.contact.friction);
  // (always written: its default changed on 7 Dec 2026; a checkpoint's case from before, without
  // the line, was resolved with "released": solver/run.cpp upgrade_signature)
  o += fmt::format("candidates = \"{}\"\n", c.contact.cracked_faces ? "cracked" : "released");
  // (always written: a checkpoint's case from before 7 Dec 2026 lacks it, and ran without:
  // solver/run.cpp upgrade_signature)
  o += fmt::format("passivity = {}\n", c.contact.passivity ? "true" : "false");
  if (!c.contact.edges) o += "edges = false\n";
  if (!c.contact.sleep) o += "sleep = false\n";
  for (const auto& m : c.materials) {
    o += fmt::format("\n[[material]]\nname = {}\nregions = [", q(m.name));
    for (std::size_t i = 0; i < m.regions.size(); ++i) o += (i ? ", " : "") + q(m.regions[i]);
    o += fmt::format("]\ndensity = {:.17g}\nyoungs_modulus = {:.17g}\npoisson_ratio = {:.17g}\n"
                     "damping = {:.17g}\nlocal_damping = {:.17g}\n",
                     m.density, m.youngs, m.poisson, m.damping, m.local_damping);
    // (only when set: checkpoints of cases resolved before the key existed still match)
    if (m.stiffness_damping > 0) o += fmt::format("stiffness_damping = {:.17g}\n", m.stiffness_damping);
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
