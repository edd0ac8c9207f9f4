// The run loop: builds the model from a validated Case, steps to the end time, writes the
// outputs of SPEC 4 on their schedule, watches for instability, writes summary.json.
#pragma once
#include <functional>
#include <string>

#include "cdem/io/case.hpp"
#include "cdem/io/run_limits.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/model/model.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {

struct RunOptions {
  std::string out_dir;
  int threads = 0;       // 0: the case's value, else all cores
  bool quiet = false;    // no progress output
  bool restart = false;  // continue the run in out_dir from its last good checkpoint
  bool overwrite = false;  // remove the results of an earlier run in out_dir first
  bool adapt_threads = true;  // follow the cores the run gets (thread_governor.hpp)
  // Under several ranks (docs/parallel.md): "halo" (each rank steps its part and a ghost zone),
  // "replicated" (each the whole model), "auto" (halo where the case allows it).
  std::string ranks_mode = "auto";
};

// Why the halo stage of a distributed run cannot step this case yet ("" when it can).
std::string halo_unsupported(const Case& c);

struct RunResult {
  int status = 0;        // 0 finished, 3 stopped unstable, 128 + signal interrupted
  std::string diagnosis;
  double wall_time_s = 0;
  std::int64_t steps = 0;
};

// A checkpoint's case signature (its resolved case, schedule keys fixed) as the code that wrote
// it meant it: a checkpoint written before a case key existed has no line for it, and the line is
// put in with the value that reproduces that code, so that a restart compares like with like
// (and `--set` of that value restarts it). simulation.release_angle (6 Dec 2026): before it,
// broken points were released by distance only, as 180 does.
std::string upgrade_signature(std::string sig);

// Meshing: read the case's mesh file or generate its geometry (both sized against the cap
// and this machine's memory, mesh_estimate.hpp).
Mesh load_mesh(const Case& c);

// The OpenMP threads of a run: `requested` (--threads) when > 0, else simulation.threads, else
// all processors; more than the processors available are used as those, with a warning.
int run_threads(const Case& c, int requested);

// Mesh + materials -> Model (the CDEM topology), with the case's names in errors.
Model build_case_model(const Case& c, const Mesh& mesh);

// A case ready to step: the model built, the charges bound (the blocks holding bar charges
// changed by make_charge_cavities), the simulation set up with its time step limited by the
// charges. `cdemblast run` and `cdemblast check` share it, so both report the same dt. The
// charges' load hooks are not added yet (they capture the charges' addresses): add them where
// the PreparedCase lives (add_charge_loads).
// The case is also checked against its mesh (case_checks.hpp) and its run size against the
// caps (run_limits.hpp) before anything runs.
struct PreparedCase {
  Simulation sim;
  BarCharges bars;
  SolidCharges solids;
  RunSize size;  // steps, field outputs, history samples
};
// Wall time of the parts of set-up (s): the CDEM topology (split nodes, interfaces, spring
// points), binding the charges (bars: segments and the blocks they cross; solid charges), the
// simulation (ties, stable time step, contact set-up).
struct SetupTimes {
  double topology = 0, charges = 0, simulation = 0;
};
PreparedCase prepare_case(const Case& c, const Mesh& mesh, SetupTimes* times = nullptr);
void add_charge_loads(PreparedCase& pc);

// Loads the stepped state (simulation, charges) of the newest readable checkpoint of the run in
// `dir` into pc, which was prepared from the same case (checked as a restart checks it: only the
// schedule keys may differ). For `cdemblast bench --case ... --from DIR`: time a late state.
void load_checkpointed_state(PreparedCase& pc, const Case& c, const std::string& dir);

// Runs the case into opt.out_dir (locked for the run; docs/checkpoint.md), writing checkpoints
// on the case's schedule, at the end and when interrupted by SIGINT / SIGTERM.
RunResult run_case(const Case& c, const RunOptions& opt);

// The case as a restart compares it: its resolved text with the keys that may change between a
// checkpoint and its restart (end time, output and history schedule, threads, step cap,
// checkpoint schedule) set to fixed values.
std::string restart_signature(const Case& c);

}  // namespace cdem
