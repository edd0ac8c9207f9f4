// The run's checks of its state (run.cpp calls them): the energy floor, the stability and
// energy-from-nothing checks at each history sample, and the diagnosis of a model without a
// finite stable time step.
#include "cdem/solver/run_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "cdem/core/error.hpp"
#include "cdem/physics/contact.hpp"
#include "cdem/solver/time_step.hpp"

namespace cdem {

namespace {

std::string describe_node(const Model& m, std::size_t n) {
  const auto b = m.node_block(n);
  const Vec3 p = m.X(n);
  return fmt::format("block {} (element {} of region '{}') at ({:.4g}, {:.4g}, {:.4g})", b,
                     m.block_elem_tag[b], m.region_names[m.block_region[b]], p.x, p.y, p.z);
}

}  // namespace

// The energy scale below which the blow-up check does not compare: the strain energy the model
// would hold at a uniform strain of 1e-8, 1/2 (1e-8)^2 sum E V over the blocks. Far above the
// rounding noise of the energies (strains of 1e-16 at t = 0) and far below any physical state
// (elastic waves in rock strain 1e-6 to 1e-3), and it scales with the model (the fixed 1e-9 J it
// replaces was a few steps of free fall of a 13.6 t cylinder, and a real energy for a small 2D
// test). 4.5e-5 J for the pile-pit model of SPEC 5.3.
double energy_floor(const Model& m) {
  double ev = 0;
  for (std::size_t b = 0; b < m.n_blocks(); ++b)
    ev += m.block_materials[m.block_material[b]].youngs * m.block_volume0[b];
  return 0.5 * 1e-16 * ev;
}

// Returns a diagnosis when the state is not finite or the energy has blown up, else "".
// Blow-up: the mechanical energy at t_n is more than `factor` x the energy put in up to t_n
// (initial + works, gravity's being the potential drop sum m g . (x_n - X)), or x the floor
// when less has been put in. Contact that makes energy: the general contacts' booked
// dissipation (friction, damping, the energy of the contacts that ended) below -contact_limit x
// that energy (0: not checked). Interfaces that make energy: their booked dissipation more than
// iface_limit x that energy below its peak so far, fracture_peak (0: not checked).
std::string check_stability(const Simulation& sim, const EnergyBalance& e, double factor,
                            double contact_limit, double iface_limit, double fracture_peak, double t,
                            double floor) {
  const Model& m = sim.model();
  if (sim.inverted_blocks() > 0) {
    const auto b = sim.first_inverted();
    return fmt::format("at t = {:.6g} s (step {}): {} block(s) inverted (volume ratio <= 0), the "
                       "first: block {} (element {} of region '{}'). The time step may be too large "
                       "or a load too strong for the mesh.",
                       t, sim.steps(), sim.inverted_blocks(), b, m.block_elem_tag[b],
                       m.region_names[m.block_region[b]]);
  }
  // Every term of the balance (a NaN or infinite term makes its exact sum NaN: a load or a work
  // that overflowed shows here even while the motion is still finite).
  const std::pair<const char*, double> terms[] = {
      {"kinetic", e.kinetic},         {"block_strain", e.block_strain},
      {"spring_strain", e.spring_strain}, {"external_work", e.external_work},
      {"gravity_work", e.gravity_work}, {"explosive_work", e.explosive_work},
      {"damping", e.damping},         {"fracture", e.fracture},
      {"insertion", e.insertion},     {"contact_strain", e.contact_strain},
      {"contact_friction", e.contact_friction}, {"products_kinetic", e.products_kinetic}};
  for (const auto& [name, value] : terms) {
    if (std::isfinite(value)) continue;
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      if (!std::isfinite(m.v[n].x + m.v[n].y + m.v[n].z))
        return fmt::format("at t = {:.6g} s (step {}): the state is not finite (NaN or Inf), first at "
                           "node {} of {}",
                           t, sim.steps(), n, describe_node(m, n));
    return fmt::format("at t = {:.6g} s (step {}): the energy balance is not finite: its term {} is {} "
                       "(energy.csv); a load or a work overflowed while the motion was still finite",
                       t, sim.steps(), name, value);
  }
  const double input = std::abs(e.initial) + std::abs(e.external_work) + std::abs(e.gravity_work) +
                       std::abs(e.explosive_work) + std::abs(e.insertion);
  if (e.mechanical() > factor * std::max(input, floor)) {
    std::size_t worst = 0;
    double vmax = -1;
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      if (norm(m.v[n]) > vmax) vmax = norm(m.v[n]), worst = n;
    return fmt::format("at t = {:.6g} s (step {}): energy blow-up: mechanical energy {:.4g} J is "
                       "more than {} x the energy put in ({:.4g} J; the model's floor {:.4g} J). "
                       "Fastest node {} ({:.4g} m/s) in {}",
                       t, sim.steps(), e.mechanical(), factor, input, floor, worst, vmax,
                       describe_node(m, worst));
  }
  // A passive contact takes energy (friction, damping) and gives back only what its penalty
  // springs stored; beyond the integration's error it makes none. A penalty contact that has
  // gone unstable (a contact too stiff for the step, blocks crushed into each other) makes it
  // fast and the energy balance still closes, since it is booked: in the coarse SPEC 5.3 scheme
  // A at dt_safety 0.8, 4.4 MJ in 0.2 ms (docs/pile_pit_3d.md). The results after that are not
  // to be trusted, so the run stops.
  if (contact_limit > 0 && e.contact_friction < -contact_limit * std::max(input, floor)) {
    // where: the node-to-face pair that has booked the most energy made (the edge contacts and
    // the contacts that ended are in the sum, not in this search)
    const ContactSet& cs = sim.contact();
    const std::size_t np = std::min(cs.pair_diss.size(), cs.pair_node.size());
    const auto worst = static_cast<std::size_t>(
        std::min_element(cs.pair_diss.begin(), cs.pair_diss.begin() + static_cast<std::ptrdiff_t>(np)) -
        cs.pair_diss.begin());
    const std::string where =
        worst < np && cs.pair_diss[worst] < 0
            ? fmt::format(" The pair that made the most: node {} of {}, against block {} ({:.4g} J).",
                          cs.pair_node[worst], describe_node(m, static_cast<std::size_t>(cs.pair_node[worst])),
                          cs.pair_block[worst], cs.pair_diss[worst])
            : std::string();
    return fmt::format("at t = {:.6g} s (step {}): contact made energy: the general contacts' booked "
                       "dissipation is {:.4g} J, more than {} x the energy put in ({:.4g} J) below "
                       "zero.{} A penalty contact has gone unstable: lower simulation.dt_safety or "
                       "contact.stiffness_factor (simulation.contact_energy_limit = 0 turns this "
                       "check off)",
                       t, sim.steps(), e.contact_friction, contact_limit, input, where);
  }
  // The interfaces' laws dissipate (breaking, softening, friction): their booked dissipation
  // grows, give or take the integration's error. One that falls by a good share of the energy
  // put in means spring points gave back far more work than they stored, and the balance still
  // closes (it is booked): in the coarse SPEC 5.3 scheme B, 5.8 MJ between two samples at
  // 22.8 ms, fragments thrown at 5.6 km/s (docs/pile_pit_3d.md), a broken point between two
  // faces turned 177 degrees apart (what simulation.release_angle now releases). The run stops.
  if (iface_limit > 0 && e.fracture < fracture_peak - iface_limit * std::max(input, floor)) {
    // where: the spring point with the lowest booked dissipation
    const auto worst = static_cast<std::size_t>(
        std::min_element(m.sp_dissipated.begin(), m.sp_dissipated.end()) - m.sp_dissipated.begin());
    std::string where;
    if (worst < m.sp_dissipated.size() && m.sp_dissipated[worst] < 0) {
      const auto i = worst / static_cast<std::size_t>(m.springs_per_iface);
      where = fmt::format(" The spring point with the lowest booked dissipation: {} of interface {} between "
                          "blocks {} and {} ({:.4g} J), at node {} of {}.",
                          worst, i, m.iface_block_a[i], m.iface_block_b[i], m.sp_dissipated[worst],
                          m.sp_a[worst], describe_node(m, static_cast<std::size_t>(m.sp_a[worst])));
    }
    const std::string angle =
        m.release_cos < -1.0
            ? " With simulation.release_angle = 180, broken points between faces turned apart are a "
              "known cause: leave it at its default."
            : "";
    return fmt::format("at t = {:.6g} s (step {}): the interfaces made energy: their booked dissipation "
                       "fell by {:.4g} J below its peak ({:.6g} J), more than {} x the energy put in "
                       "({:.4g} J).{}{} Lower simulation.dt_safety (simulation.interface_energy_limit = 0 "
                       "turns this check off)",
                       t, sim.steps(), fracture_peak - e.fracture, fracture_peak, iface_limit, input,
                       where, angle);
  }
  return {};
}

// When no finite stable time step exists, say which material or block makes it so (the
// Simulation would only say there is none).
void diagnose_time_step(const Model& m, const Case& c) {
  const StableStep st = stable_time_step(m, c.dt_safety);
  if (st.dt > 0 && std::isfinite(st.dt)) return;
  if (c.fixed_dt > 0 && std::isinf(st.dt)) return;  // nothing limits dt: the fixed one is used
  auto material = [&](std::size_t b) -> const BlockMaterial& {
    return m.block_materials[m.block_material[b]];
  };
  if (st.block >= 0 && !(st.dt_block > 0 && std::isfinite(st.dt_block))) {
    const auto b = static_cast<std::size_t>(st.block);
    const BlockMaterial& mat = material(b);
    throw InputError(fmt::format(
        "{}: material '{}': no finite stable time step: block {} (element {}) has the time limit "
        "h/c_p = {:g} s from its smallest altitude h = {:g} m and the P-wave speed c_p = {:g} m/s "
        "of youngs_modulus = {:g} Pa, poisson_ratio = {:g}, density = {:g} kg/m^3",
        c.path, mat.name, b, m.block_elem_tag[b], st.dt_block, m.block_altitude0[b], mat.cp(),
        mat.youngs, mat.poisson, mat.density));
  }
  if (st.node >= 0 && !(st.dt_spring > 0 && std::isfinite(st.dt_spring))) {
    const auto n = static_cast<std::size_t>(st.node);
    const auto b = m.node_block(n);
    throw InputError(fmt::format(
        "{}: material '{}': no finite stable time step: node {} of block {} (element {}) has mass "
        "{:g} kg against its springs' stiffness (k_n = stiffness_factor x E / h): check density "
        "and youngs_modulus",
        c.path, material(b).name, n, b, m.block_elem_tag[b], m.mass[n]));
  }
  throw InputError(fmt::format("{}: no finite stable time step: the model has no rock blocks "
                               "and no interfaces (only explosive blocks?)",
                               c.path));
}

}  // namespace cdem
