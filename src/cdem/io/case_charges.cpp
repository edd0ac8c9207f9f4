#include "cdem/io/case_sections.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "cdem/core/error.hpp"
#include "cdem/explosive/explosive_library.hpp"

namespace cdem {

namespace {

std::string builtin_list() {
  std::string s;
  for (const auto& n : builtin_explosive_names()) s += (s.empty() ? "'" : ", '") + n + "'";
  return s;
}

}  // namespace

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
  // in key order: the table is walked in its hash order, which writing the resolved case and
  // reading it back need not keep (the restart signature compares the written text)
  std::sort(c.delay_groups.begin(), c.delay_groups.end(),
            [](const DelayGroup& a, const DelayGroup& b) { return a.name < b.name; });
}

void resolve_material_explosives(Case& c) {
  for (auto& m : c.materials)
    if (!m.explosive.empty() && !c.explosive(m.explosive))
      throw InputError(fmt::format("{}: material '{}': unknown explosive '{}' (built-in: {}; or "
                                   "define it in [[explosive]])",
                                   c.path, m.name, m.explosive, builtin_list()));
    else if (!m.explosive.empty() && m.density < 0)
      m.density = explosive_density(c.explosive(m.explosive)->eos);
}

}  // namespace cdem
