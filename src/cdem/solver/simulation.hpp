// The explicit solver: one step function calling the kernels in a fixed order (positions,
// block forces, spring forces, gather, explosive loads, boundary loads, integration with
// gravity and damping, velocity constraints), plus the energy book-keeping (SPEC 4).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/prefetch.hpp"
#include "cdem/core/state_archive.hpp"
#include "cdem/io/case.hpp"
#include "cdem/model/model.hpp"
#include "cdem/physics/applied_loads.hpp"
#include "cdem/physics/boundaries.hpp"
#include "cdem/physics/contact.hpp"
#include "cdem/physics/ties.hpp"
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
  double insertion = 0;        // tied mode: elastic energy of the springs of untied points at
                               // the moment they were untied (tie_failure.hpp)
  double contact_strain = 0;   // elastic (penalty) energy held by the general contacts
  double contact_friction = 0; // dissipated by the general contacts (friction, damping)
  double products_kinetic = 0; // of `kinetic`, the charge's products' own (the explosive blocks',
                               // a bar charge block's products' mass share): not a term of the
                               // balance; explosive_work - products_kinetic is the energy the
                               // charge has given to the rock (docs/theory.md "Energy balance")
  // balance = (stored + dissipated) - (initial + work in); error = |balance| / scale
  double balance = 0, error = 0;
  double mechanical() const { return kinetic + block_strain + spring_strain + contact_strain; }
};

// An extra load applied every step after the block and spring forces (the explosive models
// plug in here): it adds its forces through AppliedLoads at time t.
using LoadHook = std::function<void(Model&, AppliedLoads&, double t)>;

// The kernels of Simulation::step in their order, for timing (cdemblast bench).
enum StepKernel {
  kStepPositions,
  kStepSprings,
  kStepBlocks,
  kStepContact,
  kStepLoads,
  kStepTies,
  kStepBoundary,
  kStepIntegrate,
  kStepWork,
  kNumStepKernels
};
constexpr const char* kStepKernelNames[kNumStepKernels] = {
    "update_positions", "spring_forces",   "block_forces", "contact",      "explosive_loads",
    "tie_failure",      "boundary_forces", "integrate",    "constraints_and_work"};
struct StepTimes {
  std::array<double, kNumStepKernels> s{};  // wall seconds per kernel, summed over the steps
};

// What the set-up of a part's local model (parallel/halo.hpp) takes from the whole model: the
// values its set-up would otherwise find over its own blocks only.
struct PartModel;
struct HaloIndex;
struct HaloGatherLists;

struct WholeModelSetup {
  double omega2_max = 0;  // tied mode: the largest omega^2 of all blocks (the opened stiffness)
  // per node of the part, the whole model's mass-proportional damping (its damping zones are
  // graded over the whole zone); empty: the part's own
  std::vector<double> damping;
  // tied mode: per node of the part, the whole model's count of its spring points (the opened
  // points' stiffness is set from it); empty: the part's own
  std::vector<std::int32_t> node_springs;
  // whether the whole model keeps its local (material) damping array: a part keeps the damping
  // arrays the whole keeps, zero or not, so that its nodes take the kernels' same paths
  bool local_damping = false;
  // the whole model's stable step (its blocks' eigenvalues are the set-up's costliest part; a
  // part's would be those of a subset, and it steps with the whole's step); null: the part's own
  const StableStep* stable = nullptr;
};

class Simulation {
 public:
  // `whole`: set up a part of a model (parallel/halo.hpp) with the whole model's values.
  Simulation(Model model, const Case& c, const WholeModelSetup* whole = nullptr);

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
  // Tied mode: omega_max^2 of the blocks (1/s^2) and the opened points' stiffness relative to
  // the springs mode's E / h (min, median).
  double omega2_max() const { return omega2_max_; }
  const OpenedStiffness& opened_stiffness() const { return opened_; }
  // tied mode: what simulation.mass_scaling_dt added (blocks 0: none; solver/time_step.hpp)
  const MassScaling& mass_scaling() const { return mass_scaling_; }
  const ContactSet& contact() const { return contact_; }
  ContactSet& contact() { return contact_; }

  // Energy terms at the last sampled step (call step(true) first for the kinetic part). Its sums
  // are exact (core/exact_sum.hpp): of a part (is_part), over the whole model, reduced over the
  // ranks (every rank calls it at once), with the bits one process gets.
  EnergyBalance energy() const;
  // The entities whose terms this Simulation's sums list: a part's own blocks, nodes, interfaces
  // and vertices (per local entity, 1 own); null masks (every entity) for a whole model.
  struct OwnMasks {
    const std::uint8_t *block = nullptr, *node = nullptr, *iface = nullptr, *vertex = nullptr;
    // entity i of a mask's kind is this Simulation's own
    static bool mine(const std::uint8_t* mask, std::size_t i) { return mask == nullptr || mask[i] != 0; }
  };
  OwnMasks own_masks() const;

  // Bytes of the solver's own arrays (per-block energies, boundary-condition arrays), beyond the
  // Model's.
  std::size_t solver_bytes() const;

  void add_load(LoadHook hook) { loads_.push_back(std::move(hook)); }
  // Drops the load hooks (a copied Simulation re-adds hooks bound to its own charges).
  void clear_loads() { loads_.clear(); }
  // With a non-null `t`, step() adds the wall time of each kernel to it.
  void set_timer(StepTimes* t) { timer_ = t; }
  // Lowers dt to safety x dt_max when another part (e.g. explosive blocks) limits it. With a
  // fixed time step (simulation.dt) above dt_max, throws InputError naming the key.
  void limit_dt(double dt_max, const std::string& what);

  // Saves or loads everything a step may change (checkpoints; solver/run_state.hpp): the time,
  // the step count, the energy accumulators, the tied mode's per-vertex state, the boundary and
  // contact state, and the model's state arrays. A loaded Simulation must have been set up from
  // the same case and mesh.
  void io_state(StateArchive& ar);

  // A distributed run (parallel/ranks.hpp): this rank computes the block kernel for the blocks
  // [block_first[rank], block_first[rank + 1]) only, and each step shares them with the other
  // ranks (block_first: one range per rank, block_ranges in parallel/partition.hpp).
  void distribute(const std::vector<std::int64_t>& block_first, int rank);

  // ---- The halo stage of a distributed run (parallel/halo.hpp; simulation_halo.cpp) ----
  // Makes this Simulation, set up from part `pm` of the model `whole` steps (with the whole's
  // WholeModelSetup and time step), that part: the sums its step and its samples form over the
  // model (the works, the energies, the inverted blocks) then list only its own entities' terms,
  // summed exactly and reduced over the ranks (step_sums, energy: the whole model's sums, the bits
  // of one process). `part`: a part per block of the whole model, rank r stepping part r.
  void make_part(const Simulation& whole, const PartModel& pm, const std::vector<std::int32_t>& part);
  bool is_part() const { return halo_ != nullptr; }
  // On the whole model's Simulation, every rank calling it at once: on rank 0, its state after
  // the step the parts have just taken, from each part's own blocks, nodes, interfaces and
  // vertices (one gather to rank 0, which writes the outputs and checkpoints); on every rank, the
  // clock, the works and the inverted blocks (what the parts hold alike). `local` is this rank's
  // part. `extra_local` / `extra_whole`: a per-node array carried along (the uplift maxima),
  // local and whole; may be null.
  void gather_parts(const Simulation& local, const std::vector<double>* extra_local, std::vector<double>* extra_whole);
  // On the whole model's Simulation, every rank calling it at once (one small gather to rank 0,
  // from the part that owns each): on rank 0, the stress of `blocks`, the velocity of `nodes` (and
  // with !velocities_only their positions and forces), and the clusters (tied mode: node lists and
  // runs) of `vertices`; each list ascending, without repeats. What a history sample writes
  // besides the exact sums: the monitors, and the reactions (their velocities before a sampled
  // step, then after it). No rank decides anything from them (the stability check's decisions come
  // from the sums), so the other ranks only send.
  void gather_sample(const Simulation& local, const std::vector<std::int32_t>& blocks,
                     const std::vector<std::int32_t>& nodes, const std::vector<std::int32_t>& vertices,
                     bool velocities_only);
  // The time and step count of the part `local`, and its inverted blocks' count and first (the
  // parts form them over the whole model): between gathers, the run loop's clock and what a
  // sample's stability check reads.
  void follow_clock(const Simulation& local) {
    t_ = local.t_, steps_ = local.steps_;
    inverted_ = local.inverted_, first_inverted_ = local.first_inverted_;
  }

 private:
  // The block kernel's results of every rank's blocks to every rank (forces, stress, strain
  // energy, volume ratio); returns the inverted-block count's maximum over the ranks.
  std::int64_t share_blocks(std::int64_t inverted);
  // This rank's share of the spring kernel's list (all of it on one rank) for this step.
  std::pair<std::int64_t, std::int64_t> spring_share();
  // The spring kernel's results of every rank's share to every rank, and the released points'
  // count (Model::released_points, `released_before` this step's kernel) summed over them.
  void share_springs(std::int64_t released_before);
  void setup_damping_zones(const Case& c);
  void setup_initial_stress(const Case& c);

  Model m_;
  Boundaries bc_;
  StableStep stable_;
  std::vector<LoadHook> loads_;
  StepTimes* timer_ = nullptr;
  AppliedLoads applied_;
  double t_ = 0, dt_ = 0;
  double fixed_dt_ = 0;     // simulation.dt, 0 when the stable step is used
  std::string case_path_;
  std::int64_t steps_ = 0;
  std::int64_t inverted_ = 0;
  std::int32_t first_inverted_ = -1;
  std::vector<double> block_dissipated_, ke_, cke_;  // per block (integrate.hpp)
  // Tied mode: per vertex (integrate_tied) and the constrained vertices; the failure flags.
  std::vector<double> vtx_dissipated_, vtx_ke_, vtx_cke_, vtx_reaction_;
  std::vector<std::uint8_t> vtx_con_;
  std::vector<std::int32_t> con_vertices_;
  std::vector<std::uint8_t> tie_flag_;
  double w_insert_ = 0, omega2_max_ = 0;
  OpenedStiffness opened_;
  MassScaling mass_scaling_;
  ContactSet contact_;
  double w_boundary_ = 0, w_absorbed_ = 0, w_explosive_ = 0, e_initial_ = 0;
  // The parts after t_n of the last step's works, F(n) . v(n+1/2) dt / 2 (energy())
  double last_boundary_ = 0, last_absorbed_ = 0, last_explosive_ = 0;
  // Stiffness-proportional damping (physics/stiffness_damping.hpp), when some material has it:
  // the step's damping force per node and power per block at v(n-1/2), the accumulated work
  // (<= 0) and its part after t_n; beta_max_ (s) enters the stable step.
  std::vector<Vec3> sd_force_;
  std::vector<double> sd_power_;
  double w_sdamp_ = 0, last_sdamp_ = 0, beta_max_ = 0;
  // Distributed run: the ranks' block and node ranges (empty on one rank), this rank's blocks.
  std::vector<std::int64_t> rank_blocks_, rank_nodes_;
  std::int32_t own_lo_ = 0, own_hi_ = std::numeric_limits<std::int32_t>::max();
  // The ranks' shares of the spring kernel's list this step (spring_share), and the buffer of
  // their packed results (pack_spring_state; sized once, at distribute).
  std::vector<std::int64_t> spring_first_;
  std::vector<double> spring_buf_;
  std::vector<std::int64_t> rank_slices_;  // scratch: the slices' offsets in spring_buf_
  int rank_ = 0;
  // The halo stage: a part's indices (make_part), the whole's gather lists (gather_parts).
  std::shared_ptr<HaloIndex> halo_;
  std::shared_ptr<const HaloGatherLists> gather_;
  // The step's works (the boundary's, the explosive loads', the insertion energy) and the
  // inverted blocks (inv of them, the first `first`), summed exactly over this Simulation's own
  // entities (a part: reduced over the ranks) into the accumulated works.
  void step_sums(std::int64_t inv, std::int32_t first);
  // a part's inverted blocks: its own blocks' count and first (global) block
  void part_inverted(std::int64_t& inv, std::int32_t& first) const;
  // Block b has inverted and is rock: a bar's charge blocks and a solid charge's explosive blocks
  // (mostly products) may collapse once their gas has left them, and the run goes on.
  bool rock_inverted(std::size_t b) const {
    const BlockMaterial& mt = m_.block_materials[m_.block_material[b]];
    return !(m_.vol_ratio[b] > 0) && !mt.charge_block && mt.explosive.empty();
  }
  std::vector<std::pair<std::int64_t, double>> insert_terms_;  // the step's untied points: (point, energy)
  std::vector<double> con_terms_;  // the step's constraints (springs mode): two powers each
};

}  // namespace cdem
