// The run loop: builds the model from a validated Case, steps to the end time, writes the
// outputs of SPEC 4 on their schedule, watches for instability, writes summary.json.
#pragma once
#include <functional>
#include <string>

#include "cdem/io/case.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

struct RunOptions {
  std::string out_dir;
  int threads = 0;       // 0: the case's value, else all cores
  bool quiet = false;    // no progress output
};

struct RunResult {
  int status = 0;        // 0 finished, 3 stopped unstable
  std::string diagnosis;
  double wall_time_s = 0;
  std::int64_t steps = 0;
};

// Meshing: read the case's mesh file or generate its geometry.
Mesh load_mesh(const Case& c);

// Mesh + materials -> Model (the CDEM topology), with the case's names in errors.
Model build_case_model(const Case& c, const Mesh& mesh);

RunResult run_case(const Case& c, const RunOptions& opt);

}  // namespace cdem
