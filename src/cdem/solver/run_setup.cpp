// A case's set-up for a run (run.hpp): its mesh, its thread count, its model, and the prepared
// simulation with its charges.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "cdem/core/resources.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/io/case_checks.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/mesh_estimate.hpp"
#include "cdem/mesh/mesh_order.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/run_checks.hpp"
#include "cdem/solver/time_step.hpp"

namespace cdem {

Mesh load_mesh(const Case& c) {
  Mesh mesh;
  if (c.mesh_file.empty()) {
    mesh = generate_mesh(*c.generate);  // sized before meshing
  } else {
    mesh = read_gmsh(c.mesh_file);
    check_model_size(static_cast<double>(mesh.num_elements()), mesh.dim,
                     fmt::format("mesh file '{}'", c.mesh_file), "");
  }
  order_mesh_spatially(mesh);  // blocks near in space near in memory (mesh_order.hpp)
  return mesh;
}

int run_threads(const Case& c, int requested) {
  const int asked = requested > 0 ? requested : c.threads;
  // The ranks of a distributed run on this machine share its cores.
  const int procs = std::max(1, available_processors() / ranks().local_size);
  if (asked <= 0) return procs;
  if (asked > procs) {
    const std::string share =
        ranks().local_size > 1 ? fmt::format(" for each of its {} ranks", ranks().local_size) : "";
    spdlog::warn("{}: {} threads asked ({}), this machine has {} processors{}: using {} (the "
                 "results do not depend on the thread count)",
                 c.path, asked, requested > 0 ? "--threads" : "key 'simulation.threads'", procs,
                 share, procs);
    return procs;
  }
  return asked;
}

Model build_case_model(const Case& c, const Mesh& mesh) {
  return build_model(mesh, c.materials, c.interfaces, c.path);
}

PreparedCase prepare_case(const Case& c, const Mesh& mesh, SetupTimes* times) {
  check_case_against_mesh(c, mesh);
  using SetupClock = std::chrono::steady_clock;
  auto lap = [times, t = SetupClock::now()](double SetupTimes::*part) mutable {
    const auto now = SetupClock::now();
    if (times) times->*part += std::chrono::duration<double>(now - t).count();
    t = now;
  };
  // Bars are bound before the simulation is set up: the blocks holding a charge change
  // material (time step, masses).
  Model model = build_case_model(c, mesh);
  lap(&SetupTimes::topology);
  const ChargeSpec spec = charge_spec(c);
  BarCharges bars = build_bar_charges(model, spec);
  const double bar_dt = make_charge_cavities(model, bars);
  SolidCharges solids = build_solid_charges(model, spec);
  products_leave_contact(model, solids);
  lap(&SetupTimes::charges);
  diagnose_time_step(model, c);
  Simulation sim(std::move(model), c);
  lap(&SetupTimes::simulation);
  if (!bars.empty()) sim.limit_dt(bar_dt, "blocks holding bar charges");
  if (!solids.empty()) sim.limit_dt(solids.dt_limit, "explosive blocks");
  if (c.mass_scaling_dt > 0 && sim.dt() < c.mass_scaling_dt * (1 - 1e-9) && sim.mass_scaling().blocks > 0)
    spdlog::warn("{}: key 'simulation.mass_scaling_dt': the run steps at {:.4g} s, below the {:.4g} s "
                 "asked: the {} limit it further (the mass was added all the same)",
                 c.path, sim.dt(), c.mass_scaling_dt, sim.stable().limit);
  const std::string dt_source =
      c.fixed_dt > 0 ? "key 'simulation.dt'"
                     : fmt::format("the stable step, limited by the {}", sim.stable().limit);
  const RunSize size = check_run_size(c, sim.dt(), dt_source);
  return {std::move(sim), std::move(bars), std::move(solids), size};
}

void add_charge_loads(PreparedCase& pc) {
  if (!pc.bars.empty())
    pc.sim.add_load([&b = pc.bars](Model& mm, AppliedLoads& out, double t) { bar_loads(mm, b, out, t); });
  if (!pc.solids.empty())
    pc.sim.add_load([&s = pc.solids](Model& mm, AppliedLoads& out, double t) { solid_loads(mm, s, out, t); });
}

}  // namespace cdem
