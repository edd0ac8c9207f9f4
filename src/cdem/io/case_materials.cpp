#include "cdem/io/case_sections.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "cdem/core/error.hpp"

namespace cdem {

namespace {

// Physical ranges of material constants. Outside the hard range a value is no density or
// modulus of any solid in SI units (and would overflow the time step: c_p = sqrt(M / rho));
// outside the usual range it is legal but looks like another unit (g/cm^3, MPa, GPa).
constexpr double kMinDensity = 1e-2, kMaxDensity = 1e6;          // kg/m^3, refused beyond
constexpr double kUsualDensity[2] = {500, 3e4};                  // kg/m^3, warned beyond
constexpr double kMinModulus = 1e3, kMaxModulus = 1e13;          // Pa, refused beyond
constexpr double kUsualModulus[2] = {1e6, 1.5e12};               // Pa, warned beyond
constexpr double kMaxStiffnessFactor = 1e4;

}  // namespace

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

namespace {

void check_modulus(const TomlTable& t, const std::string& key, double e) {
  if (!(e >= kMinModulus && e <= kMaxModulus))
    throw InputError(fmt::format("{}: {:g} Pa is no Young's modulus of a solid (expected {:g} to "
                                 "{:g} Pa; rock is 1e9-1e11 Pa, i.e. 1-100 GPa)",
                                 t.where(key), e, kMinModulus, kMaxModulus));
  if (e < kUsualModulus[0] || e > kUsualModulus[1])
    spdlog::warn("{}: {:g} Pa is unusual for rock (1e9-1e11 Pa): is it in MPa or GPa?",
                 t.where(key), e);
}

}  // namespace

void parse_materials(const TomlTable& top, Case& c) {
  // ---- block materials ----
  const auto mats = top.array_of_tables("material");
  if (mats.empty())
    throw InputError(fmt::format("{}: no [[material]]: at least one is needed (density, "
                                 "youngs_modulus, poisson_ratio, regions)",
                                 c.path));
  for (const auto& t : mats) {
    t.check_known({"name", "regions", "density", "youngs_modulus", "poisson_ratio", "damping",
                   "local_damping", "stiffness_damping", "explosive"});
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
    m.stiffness_damping = t.non_negative("stiffness_damping", 0.0);
    if (m.stiffness_damping > 1e-3)
      throw InputError(fmt::format("{}: expected a Rayleigh beta in [0, 1e-3] s (a small "
                                   "fraction of the undamped time step, docs/theory.md), got {}",
                                   t.where("stiffness_damping"), m.stiffness_damping));
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
}

}  // namespace cdem
