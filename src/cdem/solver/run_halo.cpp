// The halo stage's side of a run (run_halo.hpp): which cases it steps, and this rank's part.
#include "cdem/solver/run_halo.hpp"

#include "cdem/explosive/charges.hpp"
#include "cdem/solver/run.hpp"

namespace cdem {

std::string halo_unsupported(const Case& c) {
  if (c.contact.enabled) return "general contact (its candidates need a ghost zone of a skin's width)";
  return "";
}

std::vector<std::int32_t> halo_parts(const BlockGraph& g, int parts) {
  return have_metis() ? partition_kway(g, parts) : ranges_to_parts(block_ranges(g, parts));
}

HaloRun::HaloRun(const Case& c, const Mesh& mesh, const Simulation& whole, BarCharges& bars, SolidCharges& solids,
                 const RankInfo& rk) {
  const Model& m = whole.model();
  const BlockGraph g = block_graph(m);
  part = halo_parts(g, rk.size);
  quality = partition_quality(g, part, rk.size, charge_groups(m.n_blocks(), bars, solids));
  // (the model as prepare_case makes it before its Simulation: the bars' blocks changed by their
  // charges, the explosive blocks out of contact, the same on every rank as on one process)
  // (a whole model more while the part is cut: freed before the part is set up)
  PartModel pm = [&] {
    Model before = build_case_model(c, mesh);
    if (!bars.empty()) {
      BarCharges again = build_bar_charges(before, charge_spec(c));
      make_charge_cavities(before, again);
    }
    products_leave_contact(before, solids);
    return cut_part(before, part, rk.rank);
  }();
  own_blocks = pm.own_blocks;
  ghost_blocks = pm.ghost_blocks;
  exchange = std::make_unique<HaloExchange>(pm, part);
  Case part_case = c;
  part_case.fixed_dt = whole.dt();
  part_case.mass_scaling_limit = 1;  // (the whole model's share was checked; a part's may be larger)
  WholeModelSetup ws{whole.omega2_max(), {}, {}, !m.local_damping.empty(), &whole.stable()};
  if (m.tied) ws.node_springs = node_spring_counts(m, pm);
  if (!m.damping.empty())
    for (auto n : pm.node) ws.damping.push_back(m.damping[static_cast<std::size_t>(n)]);
  sim = std::make_unique<Simulation>(std::move(pm.model), part_case, &ws);
  sim->make_part(whole, pm, part);
  if (!bars.empty() || !solids.empty()) {
    charges = std::make_unique<HaloCharges>(bars, solids, m, pm, sim->model(), part, rk.rank);
    // (one process's hooks: the bars', then the solid charges', run_setup.cpp)
    if (!bars.empty()) sim->add_load([hc = charges.get()](Model& l, AppliedLoads& out, double t) { hc->load_bars(l, out, t); });
    if (!solids.empty())
      sim->add_load([hc = charges.get()](Model& l, AppliedLoads& out, double t) { hc->load_solids(l, out, t); });
  }
  exchange->exchange(sim->model());  // (the set-up's cluster velocities of the ghosts)
  uplift = UpliftTracker(sim->model(), up_direction(m, c.analysis.up), 0);
}

void HaloRun::step(bool sample) {
  sim->step(sample);
  exchange->exchange(sim->model());
  uplift.update(sim->model());
}

}  // namespace cdem
