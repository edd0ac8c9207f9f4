// cdemblast: the command-line program.
//   cdemblast run CASE [--out DIR] [--threads N] [--set key=value]...
//   cdemblast check CASE [--set key=value]...
//   cdemblast --version
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <omp.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>

#include "cdem/core/error.hpp"
#include "cdem/io/case.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/solver/simulation.hpp"

namespace {

int cmd_check(const std::string& path, const std::vector<std::string>& sets) {
  const cdem::Case c = cdem::load_case(path, sets);
  const cdem::Mesh mesh = cdem::load_mesh(c);
  cdem::Simulation sim(cdem::build_case_model(c, mesh), c);
  const auto& m = sim.model();
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
  fmt::print("\ndt          {:.4g} s, limited by the {} (blocks {:.4g} s, springs {:.4g} s, safety {})\n",
             sim.dt(), st.limit, st.dt_block, st.dt_spring, c.dt_safety);
  fmt::print("steps       {} to reach {} s\n", static_cast<long long>(std::ceil(c.end_time / sim.dt())), c.end_time);
  fmt::print("check       OK\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cdemblast: rock blasting with the continuous-discontinuous element method"};
  app.set_version_flag("--version", std::string("cdemblast ") + CDEM_VERSION);
  app.require_subcommand(1);
  std::string case_path, out_dir;
  int threads = 0;
  bool quiet = false;
  std::vector<std::string> sets;

  auto* run = app.add_subcommand("run", "Run a case");
  run->add_option("case", case_path, "Case file (TOML)")->required();
  run->add_option("--out,-o", out_dir, "Output directory (default: runs/<case name>)");
  run->add_option("--threads,-t", threads, "OpenMP threads (default: the case's, else all cores)")
      ->check(CLI::NonNegativeNumber);
  run->add_option("--set", sets, "Override a case key: --set simulation.end_time=1e-3");
  run->add_flag("--quiet,-q", quiet, "No progress output");

  auto* check = app.add_subcommand("check", "Validate a case, mesh it, print the model size and dt");
  check->add_option("case", case_path, "Case file (TOML)")->required();
  check->add_option("--set", sets, "Override a case key");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  try {
    if (*check) return cmd_check(case_path, sets);
    const cdem::Case c = cdem::load_case(case_path, sets);
    if (out_dir.empty()) out_dir = (std::filesystem::path("runs") / std::filesystem::path(case_path).stem()).string();
    cdem::RunOptions opt;
    opt.out_dir = out_dir;
    opt.threads = threads;
    opt.quiet = quiet;
    const auto res = cdem::run_case(c, opt);
    return res.status;
  } catch (const cdem::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
