// cdemblast: the command-line program.
//   cdemblast run CASE [--out DIR] [--threads N] [--set key=value]...
//   cdemblast check CASE [--set key=value]...
//   cdemblast report RUN... [--out DIR]
//   cdemblast study FILE [--out DIR] [--threads N] [--no-run] [--variant NAME ...] [--set KEY=VALUE ...] [-v]
//   cdemblast --version
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <omp.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <thread>

#include "cdem/core/error.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/analysis/monitors.hpp"
#include "cdem/io/case.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/solver/bench.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/run_halo.hpp"
#include "cdem/physics/ties.hpp"
#include "cdem/solver/simulation.hpp"

namespace {

// check --parts N: the METIS partition of the model into N parts and what a distributed run
// would exchange with it (docs/parallel.md).
void print_partition(const cdem::Case& c, const cdem::PreparedCase& pc, int parts) {
  const auto& m = pc.sim.model();
  const auto groups = cdem::charge_groups(m.n_blocks(), pc.bars, pc.solids);
  const cdem::BlockGraph g = cdem::block_graph(m);
  // Which stage `mpirun -np N cdemblast run` takes (docs/parallel.md): the halo stage steps the
  // METIS parts printed below; the replicated stage divides the block kernel by contiguous ranges
  // of the Hilbert order.
  if (const std::string why = cdem::halo_unsupported(c); why.empty()) {
    fmt::print("ranks       mpirun -np {}: the halo stage, each rank stepping one part below and its ghosts\n", parts);
  } else {
    const auto r = cdem::partition_quality(g, cdem::ranges_to_parts(cdem::block_ranges(g, parts)), parts, groups);
    fmt::print("ranks       mpirun -np {}: the replicated stage (the halo stage does not step {} yet), dividing "
               "the block kernel into Hilbert-order ranges: {} to {} blocks, load imbalance {:.3f}, {} "
               "interfaces between ranks ({:.2f} %)\n",
               parts, why, r.blocks_min, r.blocks_max, r.imbalance, r.edge_cut, 100 * r.edge_cut_share);
  }
  if (!cdem::have_metis()) {
    fmt::print("partition   METIS: not in this build (install libmetis-dev)\n");
    return;
  }
  // (the halo stage's partition, as `run` makes it; the charges split counted for the record)
  const auto part = cdem::halo_parts(g, parts);
  const auto q = cdem::partition_quality(g, part, parts, groups);
  fmt::print("partition   {} parts (METIS k-way): {} to {} blocks, load imbalance {:.3f}, {} interfaces "
             "cut ({:.2f} %), ghost blocks (the halo stage's vertex ring) {:.0f} (mean) / {} (max) per part, "
             "{:.2f} times the model's blocks stepped in all, {:.1f} / {} neighbours, {:.3g} / {:.3g} kB "
             "exchanged per part per step; {} of the charges split\n",
             parts, q.blocks_min, q.blocks_max, q.imbalance, q.edge_cut, 100 * q.edge_cut_share,
             q.ghosts_mean, q.ghosts_max, q.stepped_share, q.neighbours_mean, q.neighbours_max,
             q.bytes_mean / 1e3, q.bytes_max / 1e3, q.together_split);
}

int cmd_check(const std::string& path, const std::vector<std::string>& sets, int parts) {
  const cdem::Case c = cdem::load_case(path, sets);
  const cdem::Mesh mesh = cdem::load_mesh(c);
  const cdem::PreparedCase pc = cdem::prepare_case(c, mesh);
  const cdem::Simulation& sim = pc.sim;
  const auto& m = sim.model();
  cdem::locate_monitors(m, c.monitors, c.path);
  const cdem::BarCharges& bars = pc.bars;
  const cdem::SolidCharges& solids = pc.solids;
  const auto& st = sim.stable();
  fmt::print("case        {} ({})\n", c.title, path);
  fmt::print("dimension   {}D\n", m.dim);
  fmt::print("blocks      {}\n", m.n_blocks());
  fmt::print("nodes       {}\n", m.n_nodes());
  fmt::print("interfaces  {}\n", m.n_ifaces());
  fmt::print("springs     {}\n", m.n_springs());
  fmt::print("regions    ");
  for (const auto& r : m.region_names) fmt::print(" {}", r);
  fmt::print("\nface sets  ");
  for (const auto& f : m.facet_sets) fmt::print(" {}({})", f.name, f.facets.size());
  fmt::print("\n");
  if (m.tied) {
    const auto& os = sim.opened_stiffness();
    fmt::print("interfaces  tied: intact points tie their nodes ({} clusters of {} vertices); opened "
               "points k_n = {:.3g} to {:.3g} (median) x E/h, taking {} of the blocks' stability "
               "limit\n",
               cdem::count_clusters(m), m.n_vertices(), os.ratio_min, os.ratio_median,
               c.opened_stiffness);
    fmt::print("dt          {:.4g} s, limited by the {} (element eigenvalue bound 2/omega_max "
               "{:.4g} s, x 1/sqrt(1 + {}) for opened points, safety {})\n",
               sim.dt(), st.limit, st.dt_block, c.opened_stiffness, c.dt_safety);
    if (c.mass_scaling_dt > 0) fmt::print("mass        {}\n", cdem::describe_mass_scaling(sim.mass_scaling(), c.mass_scaling_dt, m.dim));
    // (the blocks' own bounds, after any mass scaling: the few smallest are what sets dt; a step
    // for simulation.mass_scaling_dt is bound x safety / sqrt(1 + eta))
    const auto bq = cdem::block_bound_quantiles(m);
    fmt::print("block bounds 2/omega_e: smallest {:.3g} s; 0.1 % of the blocks below {:.3g} s, 1 % below "
               "{:.3g} s, 10 % below {:.3g} s\n",
               bq.min, bq.q001, bq.q01, bq.q1);
  } else {
    fmt::print("interfaces  springs (SPEC 1.3): every interface a spring from t = 0\n");
    fmt::print("dt          {:.4g} s, limited by the {} (blocks {:.4g} s, springs {:.4g} s, safety {})\n",
               sim.dt(), st.limit, st.dt_block, st.dt_spring, c.dt_safety);
  }
  if (sim.contact().enabled) {
    const auto& ct = sim.contact();
    double kmin = 1e300, kmax = 0;
    for (double k : ct.kc) kmin = std::min(kmin, k), kmax = std::max(kmax, k);
    double smin = 1e300, smax = 0;
    for (double s : ct.half_skin) smin = std::min(smin, 2 * s), smax = std::max(smax, 2 * s);
    const std::string skin =
        c.contact.skin > 0 ? fmt::format("skin {:.3g} m", ct.skin)
                           : fmt::format("skin a quarter of each block's extent ({:.3g} to {:.3g} m)", smin, smax);
    fmt::print("contact     on: node against {}{}, {}, penalty {:.3g} to {:.3g} N/m, "
               "friction {}, damping ratio {}\n",
               m.dim == 3 ? "triangle" : "edge", ct.edges ? ", edge against edge" : "", skin,
               kmin, kmax,
               c.contact.friction >= 0 ? fmt::format("{}", c.contact.friction)
                                       : std::string("from the interface materials"),
               c.contact.damping_ratio);
  } else {
    fmt::print("contact     off\n");
  }
  for (const auto& b : bars.bars)
    fmt::print("bar         hole '{}' deck {}: {:.4g} m, {} segments of {:.4g} m, starts at t = {:.4g} s\n",
               b.hole, b.deck + 1, b.length, b.seg_end - b.seg_begin, b.h, b.t0);
  if (!bars.empty()) fmt::print("bar blocks  {}\n", cdem::describe_bar_binding(bars));
  for (const auto& ch : solids.charges)
    fmt::print("solid       hole '{}' deck {}\n", ch.hole, ch.deck + 1);
  if (!solids.empty()) fmt::print("explosive   {} blocks\n", solids.block.size());
  if (parts > 0) print_partition(c, pc, parts);
  fmt::print("steps       {:.0f} to reach {} s{}\n", pc.size.steps, c.end_time,
             c.max_steps > 0 && pc.size.steps < std::ceil(c.end_time / sim.dt() - 1e-9)
                 ? " (stopped earlier by simulation.max_steps)"
                 : "");
  fmt::print("outputs     {:.0f} field outputs, {:.0f} history samples\n", pc.size.field_outputs,
             pc.size.history_samples);
  fmt::print("check       OK\n");
  return 0;
}

// The report and the studies are Python (python/cdemblast, matplotlib): run one of the thin
// commands of scripts/ with Debian's python (or $CDEM_PYTHON), the script taken from the source
// tree the program was built from (or the environment variable `script_env`).
int run_python(const char* script_env, const char* script_name, const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  const char* env = std::getenv(script_env);
  const std::string script = env ? env : (fs::path(CDEM_SOURCE_DIR) / "scripts" / script_name).string();
  if (!fs::exists(script)) {
    fmt::print(stderr, "error: the script '{}' is missing\n", script);
    return 1;
  }
  const char* py_env = std::getenv("CDEM_PYTHON");
  const std::string py = py_env ? py_env : (fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  auto quote = [](const std::string& s) {
    std::string o = "'";
    for (char ch : s) o += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return o + "'";
  };
  std::string cmd = quote(py) + " " + quote(script);
  for (const auto& a : args) cmd += " " + quote(a);
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 1;
}

int cmd_report(const std::vector<std::string>& runs, const std::string& out) {
  for (const auto& r : runs)
    if (!std::filesystem::exists(std::filesystem::path(r) / "summary.json")) {
      fmt::print(stderr, "error: '{}' is not a finished run directory (no summary.json)\n", r);
      return 2;
    }
  std::vector<std::string> args = runs;
  if (!out.empty()) args.insert(args.end(), {"--out", out});
  return run_python("CDEM_REPORT_SCRIPT", "cdem_report.py", args);
}

// A study (docs/study.md): the variants are run by this very program (--bin).
int cmd_study(const std::string& file, const std::string& out, int threads, bool no_run,
              const std::vector<std::string>& sets, const std::vector<std::string>& only,
              bool verbose, const char* argv0) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) self = fs::absolute(argv0);
  std::vector<std::string> args = {file, "--bin", self.string()};
  if (!out.empty()) args.insert(args.end(), {"--out", out});
  if (threads > 0) args.insert(args.end(), {"--threads", std::to_string(threads)});
  if (no_run) args.push_back("--no-run");
  for (const auto& s : sets) args.insert(args.end(), {"--set", s});
  for (const auto& v : only) args.insert(args.end(), {"--variant", v});
  if (verbose) args.push_back("-v");
  return run_python("CDEM_STUDY_SCRIPT", "cdem_study.py", args);
}

// An error message on stderr. On several ranks every rank usually meets the same error (the same
// case): rank 0 says it; another rank says it, with its rank, only if it is still running a
// second later (rank 0 did not meet it, and ends the others when it does: RankSession::finish).
void print_error(const char* what) {
  const cdem::RankInfo& rk = cdem::ranks();
  if (rk.size > 1 && !rk.root()) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    fmt::print(stderr, "error: rank {}: {}\n", rk.rank, what);
    return;
  }
  fmt::print(stderr, "error: {}\n", what);
}

int cli_main(int argc, char** argv) {
  CLI::App app{"cdemblast: rock blasting with the continuous-discontinuous element method"};
  app.set_version_flag("--version", fmt::format("cdemblast {} (MPI: {}, METIS: {})", CDEM_VERSION,
                                                cdem::have_mpi() ? "yes" : "no",
                                                cdem::have_metis() ? "yes" : "no"));
  app.require_subcommand(1);
  std::string case_path, out_dir;
  int threads = 0;
  bool quiet = false;
  std::vector<std::string> sets;

  auto* run = app.add_subcommand("run", "Run a case");
  run->add_option("case", case_path, "Case file (TOML)")->required();
  run->add_option("--out,-o", out_dir, "Output directory (default: runs/<case name>)");
  run->add_option("--threads,-t", threads, "OpenMP threads (default: the case's, else all cores)")
      ->check(CLI::Range(0, cdem::kMaxThreads).description("an integer from 0 to 4096"));
  run->add_option("--set", sets, "Override a case key: --set simulation.end_time=1e-3")
      ->allow_extra_args(false);
  run->add_flag("--quiet,-q", quiet, "No progress output");
  std::string restart_dir;
  bool overwrite = false;
  run->add_option("--restart", restart_dir,
                  "Continue the run in this directory from its last good checkpoint (the case may "
                  "change only in end_time, the output and checkpoint schedule, threads)");
  run->add_flag("--overwrite", overwrite, "Remove the results of an earlier run in --out first");
  bool fixed_threads = false;
  run->add_flag("--fixed-threads", fixed_threads,
                "Keep the thread count (by default a run drops to the cores it actually gets when "
                "other work shares the machine, and climbs back: results do not depend on it)");
  std::string ranks_mode = "auto";
  run->add_option("--ranks-mode", ranks_mode,
                  "Under mpirun: 'halo' (each rank steps its part and a ghost zone; cases without "
                  "charges, contact or stiffness damping), 'replicated' (each rank "
                  "steps the whole model, dividing two kernels), 'auto' (halo where the case allows "
                  "it). The results are the same bits (docs/parallel.md)")
      ->check(CLI::IsMember({"auto", "halo", "replicated"}));

  std::string resume_dir;
  std::vector<std::string> resume_sets;
  auto* resume = app.add_subcommand("resume", "Continue an interrupted run from its last good checkpoint "
                                              "(its case.resolved.toml, as run --restart)");
  resume->add_option("run_dir", resume_dir, "Run directory")->required();
  resume->add_option("--threads,-t", threads, "OpenMP threads")
      ->check(CLI::Range(0, cdem::kMaxThreads).description("an integer from 0 to 4096"));
  resume->add_option("--set", resume_sets, "Change a key that may change: --set simulation.end_time=0.1")
      ->allow_extra_args(false);
  resume->add_flag("--quiet,-q", quiet, "No progress output");
  resume->add_flag("--fixed-threads", fixed_threads, "Keep the thread count (see run --fixed-threads)");

  auto* check = app.add_subcommand("check", "Validate a case, mesh it, print the model size and dt");
  check->add_option("case", case_path, "Case file (TOML)")->required();
  check->add_option("--set", sets, "Override a case key")->allow_extra_args(false);
  int check_parts = 0;
  check->add_option("--parts", check_parts,
                    "Also partition the model into this many parts with METIS and print the "
                    "partition's quality (docs/parallel.md)")
      ->check(CLI::Range(1, 1 << 20));

  std::vector<std::string> report_runs;
  std::string report_out;
  auto* report = app.add_subcommand("report", "Draw PNG plots, summary.md and index.html of finished runs");
  report->add_option("runs", report_runs, "Run directories (several: overlaid for comparison)")->required();
  report->add_option("--out,-o", report_out, "Output directory (default: RUN/report)");

  std::string study_file, study_out;
  int study_threads = 0;
  bool study_no_run = false, study_verbose = false;
  std::vector<std::string> study_sets, study_only;
  auto* study = app.add_subcommand("study", "Run the variants of a study file and compare them (docs/study.md)");
  study->add_option("file", study_file, "Study file (TOML)")->required();
  study->add_option("--out,-o", study_out, "Study directory (default: the file's [study] out)");
  study->add_option("--threads,-t", study_threads, "OpenMP threads of every run")
      ->check(CLI::Range(0, 4096).description("an integer >= 0"));
  study->add_flag("--no-run", study_no_run, "Compare the runs already in the directory");
  study->add_option("--set", study_sets, "Override a key of every variant's case, after [study] set")
      ->allow_extra_args(false);
  study->add_option("--variant", study_only,
                    "Run only this variant (repeatable; e.g. one per process), compare once all are finished");
  study->add_flag("--verbose,-v", study_verbose, "Show the runs' progress");

  cdem::BenchOptions bench_opt;
  auto* bench = app.add_subcommand("bench", "Time the step on a 3D tet model: throughput, kernel split, memory, scaling");
  bench->add_option("--blocks", bench_opt.blocks, "Approximate number of blocks (default 30000)")
      ->check(CLI::Range(1, 100000000));
  bench->add_option("--steps", bench_opt.steps, "Timed steps (default 200)")->check(CLI::Range(1, 100000000));
  bench->add_option("--threads", bench_opt.threads, "Threads (default: OMP_NUM_THREADS, else all cores)")
      ->check(CLI::Range(0, cdem::kMaxThreads));
  bench->add_option("--warmup-broken", bench_opt.warmup_broken,
                    "Warm up until this fraction of the spring points is broken (default 0.005; "
                    "larger: a later, more cracked state)")
      ->check(CLI::Range(0.0, 0.9));
  bench->add_flag("--fragmented", bench_opt.fragmented,
                  "After the warm-up release the broken points: fragments touching through "
                  "contact (with --warmup-broken 0.3: a fragmented blast state)");
  bench->add_flag("!--no-contact", bench_opt.contact, "General contact off (on by default, as in a case)");
  bench->add_flag("--json", bench_opt.json, "Print one JSON object");
  std::string bench_law = "mohr_coulomb";
  bench->add_option("--law", bench_law, "Interface law of the built-in model: mohr_coulomb or fracture_energy")
      ->check(CLI::IsMember({"mohr_coulomb", "fracture_energy"}));
  bench->add_option("--interfaces", bench_opt.interfaces,
                    "Interface mode: tied (the default of a case) or springs (the paper's form)")
      ->check(CLI::IsMember({"tied", "springs"}));
  bench->add_option("--case", bench_opt.case_path,
                    "Time this case instead of the built-in model (set-up timed by part, then the "
                    "first --steps steps)");
  bench->add_option("--set", bench_opt.sets, "With --case: override a case key")->allow_extra_args(false);
  bench->add_option("--from", bench_opt.from_run,
                    "With --case: start from the newest checkpoint of this run of the same case "
                    "(time a late, fragmented state)");
  bench->add_option("--warmup-steps", bench_opt.warmup_steps,
                    "With --case: untimed steps before the timed ones (default 0)")
      ->check(CLI::Range(static_cast<std::int64_t>(0), static_cast<std::int64_t>(100000000)));

  std::string bench_export;
  bench->add_option("--export", bench_export,
                    "Instead of timing: write the box (--blocks, --law, --interfaces) as a case, "
                    "DIR/case.toml and DIR/bench.msh, to run it as a whole process or under mpirun");
  bench->add_option("--partition", bench_opt.partition_parts,
                    "Scale projection instead of timing: partition the box (METIS) into these "
                    "part counts, e.g. 16,64,256,1024, and project the exchange (docs/parallel.md)")
      ->delimiter(',')
      ->check(CLI::Range(1, 1 << 20));
  bench->add_option("--partition-blocks", bench_opt.partition_blocks,
                    "With --partition: box sizes, e.g. 1000000,10000000 (default: --blocks)")
      ->delimiter(',')
      ->check(CLI::Range(static_cast<std::int64_t>(6), static_cast<std::int64_t>(2000000000)));
  bench->add_option("--step-ns", bench_opt.step_ns,
                    "With --partition: ns per block-step on one core (default: measured on the 30k box)")
      ->check(CLI::Range(0.0, 1e9));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;  // help and version: 0; any command-line error: 2, like input errors
  }
  // Log lines (progress, warnings, a run stopped as unstable) go to stderr with the errors;
  // stdout holds only what a command prints as its result (check's report).
  spdlog::set_default_logger(spdlog::stderr_color_mt("cdemblast"));
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  // Several ranks (mpirun -np N): `run` and `resume` step one model together; `check` is
  // rank 0's (it prints the ranks' division); the other commands are one process's work.
  const cdem::RankInfo& rk = cdem::ranks();
  if (rk.size > 1) {
    if (!rk.root()) spdlog::set_level(spdlog::level::off);  // rank 0 reports
    if (*check) {
      if (!rk.root()) return 0;
      if (check_parts == 0) check_parts = rk.size;
    } else if (!*run && !*resume) {
      if (rk.root())
        fmt::print(stderr, "error: only run, resume and check run on several MPI ranks; start this "
                           "command without mpirun\n");
      return 2;
    }
  }
  try {
    if (*check) return cmd_check(case_path, sets, check_parts);
    if (*report) return cmd_report(report_runs, report_out);
    if (*study) return cmd_study(study_file, study_out, study_threads, study_no_run, study_sets, study_only,
                                   study_verbose, argv[0]);
    if (*bench) {
      bench_opt.law = bench_law == "fracture_energy" ? cdem::InterfaceLaw::FractureEnergy
                                                     : cdem::InterfaceLaw::MohrCoulomb;
      const bool case_only = !bench_opt.sets.empty() || !bench_opt.from_run.empty() || bench_opt.warmup_steps > 0;
      if (case_only && bench_opt.case_path.empty()) {
        fmt::print(stderr, "error: bench: --set, --from and --warmup-steps go with --case FILE\n");
        return 2;
      }
      if (!bench_opt.case_path.empty() && (bench->count("--law") || bench->count("--blocks") ||
                                           bench->count("--warmup-broken"))) {
        fmt::print(stderr, "error: bench: --law, --blocks and --warmup-broken are for the built-in "
                           "model; with --case set its keys with --set\n");
        return 2;
      }
      if (!bench_export.empty()) {
        if (!bench_opt.case_path.empty()) {
          fmt::print(stderr, "error: bench: --export writes the built-in box; it does not go with --case\n");
          return 2;
        }
        return cdem::export_bench_case(bench_opt, bench_export);
      }
      if (!bench_opt.partition_parts.empty()) return cdem::run_partition_projection(bench_opt);
      return cdem::run_bench(bench_opt);
    }
    if (*resume) {
      case_path = (std::filesystem::path(resume_dir) / "case.resolved.toml").string();
      restart_dir = resume_dir;
      sets = resume_sets;
    }
    if (!restart_dir.empty()) {
      if (overwrite) {
        fmt::print(stderr, "error: --restart continues a run, --overwrite removes it: give one of them\n");
        return 2;
      }
      if (!out_dir.empty() && std::filesystem::weakly_canonical(out_dir) != std::filesystem::weakly_canonical(restart_dir)) {
        fmt::print(stderr, "error: --restart {} continues that run in its own directory; --out {} differs\n",
                   restart_dir, out_dir);
        return 2;
      }
      out_dir = restart_dir;
    }
    const cdem::Case c = cdem::load_case(case_path, sets);
    if (out_dir.empty()) out_dir = (std::filesystem::path("runs") / std::filesystem::path(case_path).stem()).string();
    cdem::RunOptions opt;
    opt.out_dir = out_dir;
    opt.threads = threads;
    opt.quiet = quiet;
    opt.restart = !restart_dir.empty();
    opt.overwrite = overwrite;
    opt.adapt_threads = !fixed_threads;
    opt.ranks_mode = ranks_mode;
    const auto res = cdem::run_case(c, opt);
    return res.status;
  } catch (const cdem::InputError& e) {
    print_error(e.what());
    return 2;
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  cdem::RankSession mpi(&argc, &argv);  // MPI when started by mpirun (parallel/ranks.hpp)
  return mpi.finish(cli_main(argc, argv));
}
