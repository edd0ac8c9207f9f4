// The explicit solver: one step function calling the kernels in a fixed order (positions,
// block forces, spring forces, gather, explosive loads, boundary loads, integration with
// gravity and damping, velocity constraints), plus the energy book-keeping (SPEC 4).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cdem/io/case.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/boundaries.hpp"
#include "cdem/solver/time_step.hpp"

namespace cdem {

struct EnergyBalance {
  double kinetic = 0;          // 1/2 m v^2 at t_n
  double block_strain = 0;     // elastic energy of the blocks
  double spring_strain = 0;    // elastic energy of the spring points
  double external_work = 0;    // boundary loads and constraint reactions
  double gravity_work = 0;     // sum m g . (x - X)
  double explosive_work = 0;   // work of the explosive loads
  double damping = 0;          // viscous + local damping + non-reflecting boundary absorption
  double fracture = 0;         // dissipated at spring points (breaking, softening, friction)
  double initial = 0;          // stored energy at t = 0 (pre-stressed springs)
  // balance = (stored + dissipated) - (initial + work in); error = |balance| / scale
  double balance = 0, error = 0;
  double mechanical() const { return kinetic + block_strain + spring_strain; }
};

// Forces applied by extra loads during a step, kept so that their work can be integrated with
// the mid-step velocity: W += F(n) . (v(n-1/2) + v(n+1/2)) / 2 dt.
struct AppliedLoads {
  std::vector<std::int32_t> node;
  std::vector<Vec3> force, v_old;
  void clear() {
    node.clear();
    force.clear();
    v_old.clear();
  }
  // Adds f to node n of the model and records it.
  void add(Model& m, std::int32_t n, Vec3 f) {
    m.f[n] += f;
    node.push_back(n);
    force.push_back(f);
    v_old.push_back(m.v[n]);
  }
};

// An extra load applied every step after the block and spring forces (the explosive models
// plug in here): it adds its forces through AppliedLoads at time t.
using LoadHook = std::function<void(Model&, AppliedLoads&, double t)>;

class Simulation {
 public:
  Simulation(Model model, const Case& c);

  // One explicit step. With sample = true the kinetic energy at t_n is evaluated.
  void step(bool sample = false);

  Model& model() { return m_; }
  const Model& model() const { return m_; }
  double time() const { return t_; }
  double dt() const { return dt_; }
  std::int64_t steps() const { return steps_; }
  const StableStep& stable() const { return stable_; }
  std::int64_t inverted_blocks() const { return inverted_; }
  std::int32_t first_inverted() const { return first_inverted_; }

  // Energy terms at the last sampled step (call step(true) first for the kinetic part).
  EnergyBalance energy() const;

  // Bytes of the solver's own arrays (per-block energies, boundary-condition arrays), beyond the
  // Model's.
  std::size_t solver_bytes() const;

  void add_load(LoadHook hook) { loads_.push_back(std::move(hook)); }
  // Lowers dt to safety x dt_max when another part (e.g. explosive blocks) limits it. With a
  // fixed time step (simulation.dt) above dt_max, throws InputError naming the key.
  void limit_dt(double dt_max, const std::string& what);

 private:
  void setup_damping_zones(const Case& c);
  void setup_initial_stress(const Case& c);

  Model m_;
  Boundaries bc_;
  StableStep stable_;
  std::vector<LoadHook> loads_;
  AppliedLoads applied_;
  double t_ = 0, dt_ = 0;
  double fixed_dt_ = 0;     // simulation.dt, 0 when the stable step is used
  std::string case_path_;
  std::int64_t steps_ = 0;
  std::int64_t inverted_ = 0;
  std::int32_t first_inverted_ = -1;
  std::vector<double> block_dissipated_, ke_, cke_;  // per block (integrate.hpp)
  double w_boundary_ = 0, w_absorbed_ = 0, w_explosive_ = 0, e_initial_ = 0;
  double last_boundary_ = 0, last_absorbed_ = 0, last_explosive_ = 0;  // increments of the last step
};

}  // namespace cdem
