#include "cdem/solver/run.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>

#include "cdem/analysis/blast_quality.hpp"
#include "cdem/analysis/damage.hpp"
#include "cdem/analysis/monitors.hpp"
#include "cdem/analysis/reactions.hpp"
#include "cdem/analysis/uplift.hpp"
#include "cdem/core/error.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/io/checkpoint.hpp"
#include "cdem/io/run_writer.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/parallel/ranks.hpp"
#include "cdem/solver/run_checks.hpp"
#include "cdem/solver/run_dir.hpp"
#include "cdem/solver/run_halo.hpp"
#include "cdem/solver/run_restart.hpp"
#include "cdem/solver/run_state.hpp"
#include "cdem/solver/simulation.hpp"
#include "cdem/solver/thread_governor.hpp"

namespace cdem {

namespace {

using Clock = std::chrono::steady_clock;

// The bits of some doubles mixed into one word (FNV-1a), for the ranks of a distributed run to
// check that they agree (same_over_ranks).
std::uint64_t hash_bits(std::initializer_list<double> xs) {
  std::uint64_t h = 1469598103934665603ull;
  for (double x : xs) {
    std::uint64_t u;
    std::memcpy(&u, &x, sizeof u);
    h = (h ^ u) * 1099511628211ull;
  }
  return h;
}

// The energy terms' bits: every term is a sum over the whole model, so a rank whose state
// differs in any block moves at least one of them.
std::uint64_t energy_bits(const EnergyBalance& e) {
  return hash_bits({e.kinetic, e.block_strain, e.spring_strain, e.fracture, e.damping,
                    e.external_work, e.explosive_work, e.gravity_work, e.contact_strain,
                    e.contact_friction, e.insertion});
}

}  // namespace


namespace {
// summary.json: where the run's largest contact penetration was reached (null: none, or a run
// continued from a checkpoint written before this was kept, until it grows again).
std::string max_penetration_json(const Model& m, const ContactSet& cs) {
  const auto& r = cs.max_pen_at;
  const auto nb = static_cast<std::int32_t>(m.n_blocks());
  const bool edge = r.node < 0;
  const bool valid = r.block >= 0 && r.block < nb &&
                     (edge ? r.node == -1 && r.other >= 0 && r.other < nb
                           : r.node < static_cast<std::int32_t>(m.n_nodes()) && r.other == -1);
  if (!valid) return "null";
  std::string o = fmt::format("{{\"time\": {}, \"kind\": {}, ", json_number(r.time),
                              json_string(edge ? "edge_edge" : "node_face"));
  if (edge)
    o += fmt::format("\"blocks\": [{}, {}], ", r.block, r.other);
  else
    o += fmt::format("\"node\": {}, \"node_block\": {}, \"block\": {}, ", r.node, m.node_block(static_cast<std::size_t>(r.node)), r.block);
  const std::int32_t reg = m.block_region[static_cast<std::size_t>(r.block)];
  o += fmt::format("\"region\": {}, \"x\": [{}, {}, {}]}}",
                   reg >= 0 && static_cast<std::size_t>(reg) < m.region_names.size() ? json_string(m.region_names[reg]) : "null",
                   json_number(r.x.x), json_number(r.x.y), json_number(r.x.z));
  return o;
}

// summary.json: the region names by index, the fracture degree per region, the largest
// displacement along up (all blocks, and rock blocks only) and where.
void add_region_and_uplift_summary(std::vector<std::pair<std::string, std::string>>& kv,
                                   const Model& m, const UpliftTracker& uplift) {
  std::string names = "[";
  for (std::size_t r = 0; r < m.region_names.size(); ++r)
    names += (r ? ", " : "") + json_string(m.region_names[r]);
  kv.emplace_back("regions", names + "]");
  const RegionFracture rf = fracture_degree_by_region(m);
  std::string fr = "{";
  for (std::size_t k = 0; k < rf.regions.size(); ++k)
    fr += fmt::format("{}{}: {}", k ? ", " : "", json_string(m.region_names[rf.regions[k]]),
                      json_number(rf.degree[k]));
  kv.emplace_back("fracture_degree_regions", fr + "}");
  const auto all = uplift.peak(m, false), rock = uplift.peak(m, true);
  kv.emplace_back("max_up_displacement_m", json_number(all.value));
  kv.emplace_back("max_up_displacement_point",
                  fmt::format("[{}, {}, {}]", json_number(all.where.x), json_number(all.where.y),
                              json_number(all.where.z)));
  kv.emplace_back("max_up_displacement_rock_m", json_number(rock.value));
}
}  // namespace

RunResult run_case(const Case& c, const RunOptions& options) {
  const auto wall0 = Clock::now();
  // A distributed run (parallel/ranks.hpp): every rank steps the same state; rank 0 alone
  // writes, prints and checkpoints.
  const RankInfo& rk = ranks();
  const bool root = rk.root();
  RunOptions opt = options;
  if (!root) opt.quiet = true;
  const int threads = run_threads(c, opt.threads);
  omp_set_num_threads(threads);

  // The directory is the run's alone: locked, and either a restart of the run in it or cleared of
  // an earlier run's results (refused without --overwrite) before anything is written.
  std::optional<RunDirLock> lock;
  if (root) lock.emplace(opt.out_dir);
  std::string signature = restart_signature(c);
  std::optional<StateArchive> ckpt;
  if (opt.restart) {
    ckpt.emplace(load_last_checkpoint(opt.out_dir, opt.quiet));
    check_checkpoint_case(*ckpt, c, opt.out_dir, signature);
  } else if (root) {
    prepare_run_dir(opt.out_dir, opt.overwrite);
  }

  Mesh mesh = load_mesh(c);
  PreparedCase pc = prepare_case(c, mesh);
  add_charge_loads(pc);
  Simulation& sim = pc.sim;
  const Model& m = sim.model();
  const auto monitors = locate_monitors(m, c.monitors, c.path);
  BarCharges& bars = pc.bars;
  SolidCharges& solids = pc.solids;
  const auto st = sim.stable();
  // The halo stage (parallel/halo.hpp, docs/parallel.md): each rank steps its METIS part and a
  // ghost zone (`halo`), receives its ghosts' motion from their owners each step; the sums over
  // the model are exact, reduced over the ranks, and the whole model's state (`sim`, set up on
  // every rank) is gathered to rank 0 when it writes. A restart continues in the replicated stage
  // (the checkpoint is the whole model's).
  PartitionQuality rank_q;
  std::vector<std::int32_t> rank_part;  // the rank stepping each block (partition.vtu)
  std::string ranks_mode = rk.size > 1 ? "replicated" : "one";
  std::optional<HaloRun> halo;
  if (rk.size > 1 && opt.ranks_mode != "replicated") {
    std::string why = halo_unsupported(c);
    if (why.empty() && opt.restart) why = "a restart (it continues in the replicated stage)";
    if (!why.empty() && opt.ranks_mode == "halo")
      throw InputError(fmt::format("--ranks-mode halo: the halo stage does not step {} yet", why));
    if (!why.empty() && !opt.quiet) spdlog::info("ranks: the replicated stage, as the halo stage does not step {} yet", why);
    if (why.empty()) {
      halo.emplace(c, mesh, sim, bars, solids, rk);
      rank_q = halo->quality;
      rank_part = halo->part;
      ranks_mode = "halo";
      if (!opt.quiet)
        spdlog::info("{} ranks ({} on this machine), the halo stage: {} parts by {}, {}-{} blocks each, "
                     "imbalance {:.3f}, {:.2f} % of the interfaces between parts; this rank: {} own and "
                     "{} ghost blocks, {} neighbours",
                     rk.size, rk.local_size, rk.size, have_metis() ? "METIS" : "ranges of the block order",
                     rank_q.blocks_min, rank_q.blocks_max, rank_q.imbalance, 100 * rank_q.edge_cut_share,
                     halo->own_blocks, halo->ghost_blocks, halo->exchange->peers().size());
    }
  }
  // The replicated stage: every rank steps the whole model; the block kernel is divided among the
  // ranks by contiguous ranges of the Hilbert order.
  if (rk.size > 1 && !halo) {
    const auto groups = charge_groups(m.n_blocks(), bars, solids);
    const BlockGraph g = block_graph(m, groups);
    const auto rank_blocks = block_ranges(g, rk.size);
    sim.distribute(rank_blocks, rk.rank);
    rank_part = ranges_to_parts(rank_blocks);
    rank_q = partition_quality(g, rank_part, rk.size, groups);
    if (!opt.quiet)
      spdlog::info("{} ranks ({} on this machine): {}-{} blocks each, imbalance {:.3f}, {:.2f} % of "
                   "the interfaces between ranks, {} charges across ranks",
                   rk.size, rk.local_size, rank_q.blocks_min, rank_q.blocks_max, rank_q.imbalance,
                   100 * rank_q.edge_cut_share, rank_q.together_split);
  }
  if (!opt.quiet)
    spdlog::info("{}: {} blocks, {} nodes, {} spring points, {} interfaces; dt = {:.4g} s limited "
                 "by the {} (blocks {:.4g} s, springs {:.4g} s, safety {}); {} threads",
                 c.title, m.n_blocks(), m.n_nodes(), m.n_springs(), m.tied ? "tied" : "spring",
                 sim.dt(), st.limit, st.dt_block, st.dt_spring, c.dt_safety, threads);
  if (!opt.quiet && c.mass_scaling_dt > 0)
    spdlog::info("mass: {}", describe_mass_scaling(sim.mass_scaling(), c.mass_scaling_dt, m.dim));

  // The run loop's own state (saved in checkpoints with the objects it steps).
  std::string run_id = new_run_id();
  double next_hist = 0;
  std::vector<double> peak_vm(c.monitors.size(), 0.0), peak_vm_time(c.monitors.size(), 0.0);
  EnergyBalance last{};
  StepTimes kernel_times;
  double wall_before = 0, loop_before = 0;  // of the runs before a restart
  double wall_so_far = 0, loop_so_far = 0;  // saved: the times up to the checkpoint
  const bool has_charges = !bars.empty() || !solids.empty();
  // max displacement along up, per node and monitor
  UpliftTracker uplift(m, up_direction(m, c.analysis.up), c.monitors.size());
  // Everything the loop steps, listed once for saving and loading (the writer loads its own
  // position in its constructor, below).
  auto io_run_state = [&](StateArchive& ar) {
    sim.io_state(ar);
    io_state(ar, bars);
    io_state(ar, solids);
    uplift.io_state(ar);
    ar.io("run.id", run_id);
    ar.io("run.next_hist", next_hist);
    ar.io("run.peak_vm", peak_vm);
    ar.io("run.peak_vm_time", peak_vm_time);
    ar.io("run.last_energy", last);
    ar.io("run.kernel_times", kernel_times.s);
    ar.io("run.wall_time", wall_so_far);
    ar.io("run.loop_time", loop_so_far);
  };
  if (ckpt) {  // (the same case, so the same model sizes and monitors: checked above)
    io_run_state(*ckpt);
    // Each rank read the newest good checkpoint it found: all must continue from the same one
    // (else their exchanges would not match and the run would hang).
    // (the step count below 2^53 (check_run_size): exact as a double)
    if (rk.size > 1 && !same_over_ranks(hash_bits({sim.time(), static_cast<double>(sim.steps())})))
      throw InputError(fmt::format("--restart {}: the ranks found different checkpoints (rank {} "
                                   "continues from step {}); every rank must read the same run "
                                   "directory, on a shared file system",
                                   opt.out_dir, rk.rank, sim.steps()));
    wall_before = wall_so_far;
    loop_before = loop_so_far;
    if (!opt.quiet)
      spdlog::info("continuing run {} from t = {:.6g} s (step {})", run_id, sim.time(), sim.steps());
  }
  std::optional<RunWriter> out;
  if (root) out.emplace(opt.out_dir, c, &m, run_id, has_charges ? charge_csv_header() : "", ckpt ? &*ckpt : nullptr);
  if (out && !rank_part.empty()) out->write_partition(m, rank_part);
  // reactions.csv (constrained face sets)
  ReactionMeter reactions(m, c.boundaries, c.gravity, c.path);
  // What a history sample of the halo stage gathers besides its exact sums (ascending, without
  // repeats): the monitor blocks' stress; the velocities, positions and forces of their nodes and
  // of the nodes the reactions read, and those nodes' vertex clusters (tied mode); and before a
  // sampled step, the velocities the reactions keep.
  std::vector<std::int32_t> reaction_nodes = reactions.watched_nodes();
  auto ascending = [](std::vector<std::int32_t>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  };
  ascending(reaction_nodes);
  std::vector<std::int32_t> sample_blocks = monitors, sample_nodes = reaction_nodes, sample_vertices;
  ascending(sample_blocks);
  for (auto b : sample_blocks)
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) sample_nodes.push_back(n);
  ascending(sample_nodes);
  if (m.tied)
    for (auto n : reaction_nodes) sample_vertices.push_back(m.node_vertex[static_cast<std::size_t>(n)]);
  ascending(sample_vertices);
  const double e_floor = energy_floor(m);
  // the interfaces' booked dissipation's peak so far (after a restart: from the state's)
  double fracture_peak = -std::numeric_limits<double>::infinity();
  if (!opt.quiet && !bars.empty()) spdlog::info("bar charges: {}", describe_bar_binding(bars));

  if (!opt.quiet && !solids.empty())
    spdlog::info("solid charges: {} decks, {} explosive blocks", solids.charges.size(), solids.block.size());
  // Field output times: t = 0, every output_interval, the listed times, the end.
  std::vector<double> field_times = c.output_times;
  if (c.output_interval > 0)
    for (double t = 0; t < c.end_time * (1 - 1e-12); t += c.output_interval) field_times.push_back(t);
  field_times.push_back(0.0);
  field_times.push_back(c.end_time);
  std::sort(field_times.begin(), field_times.end());
  field_times.erase(std::unique(field_times.begin(), field_times.end(),
                                [](double a, double b) { return std::abs(a - b) < 1e-15; }),
                    field_times.end());

  const double dt = sim.dt();
  // Counted by check_run_size (prepare_case): at most 2^53, so the conversion is exact.
  const auto steps_limit = static_cast<std::int64_t>(pc.size.steps);
  std::size_t next_field = 0;
  if (ckpt) {  // the field times the run before the restart had reached (see the loop)
    const double t_done = sim.time() - dt;
    while (next_field < field_times.size() && field_times[next_field] <= t_done + 0.5 * dt) ++next_field;
  }
  RunResult res;
  const bool tty = isatty(2) && !opt.quiet;
  auto last_print = Clock::now();
  // The charges' gas pressure on the crack faces, per interface (the larger of the bar and the
  // solid charges' gas fields), for the cracks VTU.
  std::vector<float> crack_gas;
  auto gas_on_cracks = [&]() -> const std::vector<float>* {
    const auto& a = bars.gas.iface_gas_p;
    const auto& b = solids.gas.iface_gas_p;
    if (a.empty() && b.empty()) return nullptr;
    crack_gas.assign(m.n_ifaces(), 0.0f);
    for (const auto* g : {&a, &b})
      if (g->size() == crack_gas.size())
        for (std::size_t i = 0; i < crack_gas.size(); ++i) crack_gas[i] = std::max(crack_gas[i], (*g)[i]);
    return &crack_gas;
  };
  // Wall time per step kernel (summary.json kernel_time_s; a few clock reads per step).
  (halo ? *halo->sim : sim).set_timer(&kernel_times);
  const auto loop0 = Clock::now();
  auto elapsed = [](Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
  };

  // A checkpoint of the state after the step just taken (atomic; the newest two are kept).
  auto last_checkpoint = Clock::now();
  double checkpoint_s = 0;
  std::int64_t checkpoints = 0;
  std::uintmax_t checkpoint_bytes = 0;
  auto write_state = [&]() {
    if (!out) return;
    const auto t0 = Clock::now();
    out->check_written();
    StateArchive ar(false);
    ar.io("run.case_signature", signature);
    wall_so_far = wall_before + elapsed(wall0);
    loop_so_far = loop_before + elapsed(loop0);
    io_run_state(ar);
    out->io_state(ar);
    std::filesystem::create_directories(checkpoint_dir(opt.out_dir));
    const std::string path = checkpoint_path(opt.out_dir, sim.steps());
    write_checkpoint(path, ar);
    prune_checkpoints(opt.out_dir, 2);
    last_checkpoint = Clock::now();
    checkpoint_s += elapsed(t0);
    ++checkpoints;
    std::error_code ec;
    checkpoint_bytes = std::filesystem::file_size(path, ec);
  };
  double next_ckpt = c.checkpoint_interval > 0
                         ? (std::floor(sim.time() / c.checkpoint_interval) + 1) * c.checkpoint_interval
                         : 0.0;

  install_stop_signals();
  struct SignalGuard {
    ~SignalGuard() { restore_default_signals(); }
  } signal_guard;
  const std::int64_t k0 = sim.steps();
  // The thread count follows the cores the run gets (thread_governor.hpp): results do not depend
  // on it.
  ThreadGovernor governor(threads, opt.adapt_threads);
  for (std::int64_t k = k0; k < steps_limit; ++k) {
    const double t_state = sim.time();  // the state after this step is at t_n = this time
    const bool hist = t_state >= next_hist - 0.5 * dt || k + 1 == steps_limit;
    if (hist) reactions.before_step(m);
    const auto step0 = Clock::now();
    const bool field = next_field < field_times.size() && t_state >= field_times[next_field] - 0.5 * dt;
    // (the next sample's time; an interval below dt samples every step: stepping by it could
    // stall, 1e-30 + t == t)
    if (hist)
      while (next_hist <= t_state + 0.5 * dt) next_hist += std::max(c.history_interval, dt);
    if (halo)
      halo->step(hist);
    else
      sim.step(hist);
    // A signal reaches the ranks at different steps: they stop together, at the step of the first
    // to see it. A checkpoint on the wall clock is due by rank 0's clock (it alone writes).
    std::int64_t flags = 2 * static_cast<std::int64_t>(stop_signal()) +
                         (root && c.checkpoint_wall_interval > 0 && elapsed(last_checkpoint) >= c.checkpoint_wall_interval);
    if (rk.size > 1) flags = max_over_ranks(flags);
    const int sig = static_cast<int>(flags / 2);
    const bool wall_checkpoint = (flags & 1) != 0;
    // The halo stage: the whole model's state where the loop reads all of it (fields,
    // checkpoint, end or stop); at a history sample only what it reads besides its exact sums;
    // and with reactions to measure, before a sampled step the velocities they keep.
    bool whole_state = !halo;
    if (halo) {
      const Simulation& part_sim = *halo->sim;
      const bool next_hist_due = !reactions.empty() && (part_sim.time() >= next_hist - 0.5 * dt || k + 2 == steps_limit);
      whole_state = field || k + 1 == steps_limit || sig != 0 || wall_checkpoint ||
                    (c.checkpoint_interval > 0 && part_sim.time() >= next_ckpt - 0.5 * dt);
      if (whole_state) {
        sim.gather_parts(part_sim, &halo->uplift.per_node(), &uplift.per_node());
      } else {
        sim.follow_clock(part_sim);
        if (hist) sim.gather_sample(part_sim, sample_blocks, sample_nodes, sample_vertices, false);
      }
      if (next_hist_due) sim.gather_sample(part_sim, {}, reaction_nodes, {}, true);
    }
    if (const std::string msg = governor.after_step(elapsed(step0)); !msg.empty() && !opt.quiet)
      spdlog::info("{}", msg);
    if (!halo) uplift.update(m);
    if (hist) {
      // (the halo stage: the sums of each rank's part, reduced exactly over the ranks)
      const Simulation& summed = halo ? *halo->sim : sim;
      const Simulation::OwnMasks own = summed.own_masks();
      const SumReducer* reducer = halo ? rank_reducer() : nullptr;
      last = summed.energy();
      const FractureSummary fs = fracture_summary(summed.model(), own.iface, reducer);
      // The ranks' states are the same bits (ranks.hpp): checked at each sample.
      if (rk.size > 1 && !same_over_ranks(energy_bits(last)))
        throw std::runtime_error(fmt::format("the ranks' states differ at step {} (t = {:.6g} s): "
                                             "a defect of the distributed run; please report it",
                                             k, t_state));
      if (out) out->write_history(m, t_state, last, fs.degree, fs.by_region.degree, monitors);
      uplift.sample_monitors(m, monitors, t_state);
      if (!reactions.empty()) {
        reactions.after_step(m, dt, t_state + 0.5 * dt);
        if (out) out->write_reactions(t_state, reactions.face_sets(), reactions.forces());
      }
      if (out && out->charges_csv()) write_charge_rows(out->charges_csv(), t_state, bars, solids);
      for (std::size_t q = 0; q < monitors.size(); ++q) {
        const double vm = von_mises(m.stress[monitors[q]]);
        if (vm > peak_vm[q]) peak_vm[q] = vm, peak_vm_time[q] = t_state;
      }
      fracture_peak = std::max(fracture_peak, last.fracture);
      res.diagnosis = check_stability(sim, last, c.energy_blowup_factor, c.contact_energy_limit,
                                      c.interface_energy_limit, fracture_peak, t_state, e_floor);
      if (!res.diagnosis.empty() && !whole_state) {
        // (every rank found it from the same sums: the whole state for the message and the fields)
        sim.gather_parts(*halo->sim, &halo->uplift.per_node(), &uplift.per_node());
        whole_state = true;
        res.diagnosis = check_stability(sim, last, c.energy_blowup_factor, c.contact_energy_limit,
                                        c.interface_energy_limit, fracture_peak, t_state, e_floor);
      }
      if (!res.diagnosis.empty()) {
        if (out) {
          out->write_fields(m, t_state, &uplift.per_node(), gas_on_cracks());
          out->flush();
        }
        res.status = 3;
        spdlog::error("run stopped: {}", res.diagnosis);
        spdlog::error("the output written so far is in {}", opt.out_dir);
        break;
      }
    }
    if (field || k + 1 == steps_limit) {
      while (next_field < field_times.size() && field_times[next_field] <= t_state + 0.5 * dt) ++next_field;
      if (out) {
        out->write_fields(m, t_state, &uplift.per_node(), gas_on_cracks());
        out->check_written();
      }
    }
    if (sig != 0) {
      write_state();
      res.status = 128 + sig;
      res.diagnosis = fmt::format("interrupted by {} at t = {:.6g} s (step {}); continue it with "
                                  "cdemblast run CASE --restart {}",
                                  sig == SIGINT ? "SIGINT" : "SIGTERM", sim.time(), sim.steps(),
                                  opt.out_dir);
      if (tty) fmt::print(stderr, "\n");
      spdlog::warn("{}", res.diagnosis);
      break;
    }
    if (k + 1 == steps_limit ||
        (c.checkpoint_interval > 0 && sim.time() >= next_ckpt - 0.5 * dt) ||
        wall_checkpoint) {
      write_state();
      if (c.checkpoint_interval > 0)
        while (next_ckpt <= sim.time() + 0.5 * dt) next_ckpt += c.checkpoint_interval;
    }
    if (!opt.quiet) {
      const auto now = Clock::now();
      const double since = std::chrono::duration<double>(now - last_print).count();
      if ((tty && since > 0.5) || (!tty && since > 10.0)) {
        last_print = now;
        const double el = std::chrono::duration<double>(now - loop0).count();
        const double rate = (k + 1 - k0) / std::max(el, 1e-9);
        const double eta = (steps_limit - k - 1) / rate;
        const std::string line = fmt::format("t = {:.4e} s  step {}/{}  {:.0f} steps/s  ETA {:.0f} s",
                                             t_state, k + 1, steps_limit, rate, eta);
        if (tty)
          fmt::print(stderr, "\r{}   ", line);
        else
          spdlog::info("{}", line);
      }
    }
  }
  if (tty && res.status == 0) fmt::print(stderr, "\n");
  res.steps = sim.steps();
  if (!out) return res;  // not rank 0: the output is rank 0's
  out->flush();
  res.wall_time_s = wall_before + std::chrono::duration<double>(Clock::now() - wall0).count();
  const double loop_s = loop_before + std::chrono::duration<double>(Clock::now() - loop0).count();
  const double loop_this = std::chrono::duration<double>(Clock::now() - loop0).count();
  const FractureDegree fd = fracture_degree(m);
  const char* status = res.status == 0 ? "finished" : res.status == 3 ? "unstable" : "interrupted";
  std::vector<std::pair<std::string, std::string>> kv = {
      {"title", json_string(c.title)},
      {"run_id", json_string(run_id)},
      {"status", json_string(status)},
      {"diagnosis", json_string(res.diagnosis)},
      {"end_time", json_number(sim.time())},
      {"restarted_at_step", std::to_string(k0)},
      {"wall_time_s", json_number(res.wall_time_s)},
      {"loop_time_s", json_number(loop_s)},
      {"threads", std::to_string(threads)},
      {"ranks", std::to_string(rk.size)},
      {"ranks_imbalance", json_number(rk.size > 1 ? rank_q.imbalance : 1.0)},
      {"ranks_charges_split", std::to_string(rank_q.together_split)},
      {"ranks_mode", json_string(ranks_mode)},
      {"threads_adaptive", opt.adapt_threads && threads > 1 ? "true" : "false"},
      {"threads_final", std::to_string(governor.threads())},
      {"threads_switches", std::to_string(governor.switches())},
      {"threads_step_seconds", [&] {
         std::string a = "[";
         for (std::size_t i = 0; i < governor.seconds_at().size(); ++i)
           a += (i ? ", " : "") + json_number(governor.seconds_at()[i]);
         return a + "]";
       }()},
      {"steps", std::to_string(res.steps)},
      {"dt", json_number(dt)},
      {"dt_limit", json_string(st.limit)},
      {"interfaces", json_string(m.tied ? "tied" : "springs")},
      {"untied_points", std::to_string(m.tied ? static_cast<long long>(std::count(m.sp_tied.begin(), m.sp_tied.end(), 0)) : 0LL)},
      {"opened_stiffness_ratio_min", json_number(sim.opened_stiffness().ratio_min)},
      {"opened_stiffness_ratio_median", json_number(sim.opened_stiffness().ratio_median)},
      {"mass_scaling_blocks", std::to_string(sim.mass_scaling().blocks)},
      {"mass_scaling_added_kg", json_number(sim.mass_scaling().added)},
      {"mass_scaling_added_share", json_number(sim.mass_scaling().share())},
      {"mass_scaling_max_factor", json_number(sim.mass_scaling().max_factor)},
      {"insertion_energy", json_number(last.insertion)},
      {"contact", json_string(sim.contact().enabled ? "on" : "off")},
      {"contact_pairs_max", std::to_string(sim.contact().active_max)},
      {"contact_candidate_pairs", std::to_string(sim.contact().pair_node.size())},
      {"contact_buffer_pairs", std::to_string(sim.contact().pair_capacity())},
      {"contact_rebuilds", std::to_string(sim.contact().rebuilds)},
      {"contact_edge_pairs_max", std::to_string(sim.contact().ec_active_max)},
      {"contact_max_penetration_ratio", json_number(sim.contact().max_pen_ratio)},
      {"contact_max_penetration_at", max_penetration_json(m, sim.contact())},
      {"contact_energy", json_number(last.contact_strain)},
      {"contact_dissipated", json_number(last.contact_friction)},
      {"dt_blocks", json_number(st.dt_block)},
      {"dt_springs", json_number(st.dt_spring)},
      {"blocks", std::to_string(m.n_blocks())},
      {"nodes", std::to_string(m.n_nodes())},
      {"spring_points", std::to_string(m.n_springs())},
      {"block_steps_per_s", json_number(m.n_blocks() * static_cast<double>(res.steps - k0) / loop_this)},
      {"spring_steps_per_s", json_number(m.n_springs() * static_cast<double>(res.steps - k0) / loop_this)},
      {"fracture_degree", json_number(fd.area)},
      {"fracture_degree_tensile", json_number(fd.tensile)},
      {"fracture_degree_shear", json_number(fd.shear)},
      {"fracture_degree_count", json_number(fd.count)},
      {"energy_error", json_number(last.error)},
      {"kinetic_energy", json_number(last.kinetic)},
      {"explosive_work", json_number(last.explosive_work)},
      {"products_kinetic_energy", json_number(last.products_kinetic)},
      {"explosive_work_to_rock", json_number(last.explosive_work - last.products_kinetic)},
      {"bar_segments", std::to_string(bars.n_segments())},
      {"explosive_blocks", std::to_string(solids.block.size())},
      {"collapsed_explosive_blocks", std::to_string(solids.dead_count)},
      {"field_outputs", std::to_string(out->field_outputs())},
      {"checkpoints_written", std::to_string(checkpoints)},
      {"checkpoint_write_time_s", json_number(checkpoint_s)},
      {"checkpoint_bytes", std::to_string(checkpoint_bytes)},
  };
  {  // where the loop's time went: each step kernel, and the rest (analysis, outputs, samples)
    std::string kt = "{";
    double in_step = 0;
    for (int k = 0; k < kNumStepKernels; ++k) {
      kt += fmt::format("{}{}: {}", k ? ", " : "", json_string(kStepKernelNames[k]),
                        json_number(kernel_times.s[k]));
      in_step += kernel_times.s[k];
    }
    kt += fmt::format(", \"outside_step\": {}}}", json_number(std::max(0.0, loop_s - in_step)));
    kv.emplace_back("kernel_time_s", kt);
  }
  // Blasting quality of the final state: fragments, grading (main rock mass excluded), funnel.
  std::vector<std::pair<Vec3, Vec3>> hole_axes;  // collar, direction into the rock
  for (const auto& h : c.holes) hole_axes.emplace_back(h.collar, normalized(h.end - h.collar));
  const BlastQuality bq = blast_quality(m, c.analysis, c.boundaries, hole_axes);
  {
    std::FILE* g = std::fopen((std::filesystem::path(opt.out_dir) / "grading.csv").string().c_str(), "w");
    if (g) {
      std::fputs("size,passing_pct\n", g);
      for (std::size_t i = 0; i < bq.grading.size.size(); ++i)
        std::fprintf(g, "%.9g,%.9g\n", bq.grading.size[i], bq.grading.passing_pct[i]);
      std::fclose(g);
    }
  }
  std::size_t nfrag = 0;
  for (const auto& f : bq.fragments.fragments) nfrag += f.volume > 0;
  kv.emplace_back("fragments", std::to_string(nfrag));
  kv.emplace_back("main_fragment_volume",
                  json_number(bq.main_fragment >= 0 ? bq.fragments.fragments[bq.main_fragment].volume : 0.0));
  for (int i = 0; i < 9; ++i)
    kv.emplace_back(fmt::format("d{}_m", 10 * (i + 1)), json_number(bq.grading.d[i]));
  kv.emplace_back("funnel_depth_m", json_number(bq.funnel.depth));
  kv.emplace_back("funnel_lx_m", json_number(bq.funnel.l_x));
  kv.emplace_back("funnel_ly_m", json_number(bq.funnel.l_y));
  kv.emplace_back("funnel_axial_ratio", json_number(bq.funnel.axial_ratio));
  kv.emplace_back("footage_m", json_number(bq.funnel.footage));
  kv.emplace_back("funnel_broken_volume", json_number(bq.funnel.broken_volume));
  std::string peaks = "{";
  for (std::size_t q = 0; q < monitors.size(); ++q)
    peaks += fmt::format("{}{}: {{\"peak_von_mises\": {}, \"time\": {}, \"max_up_displacement\": {}, "
                         "\"max_up_time\": {}}}",
                         q ? ", " : "", json_string(c.monitors[q].name), json_number(peak_vm[q]),
                         json_number(peak_vm_time[q]), json_number(uplift.monitor_max()[q]),
                         json_number(uplift.monitor_time()[q]));
  kv.emplace_back("monitors", peaks + "}");
  add_region_and_uplift_summary(kv, m, uplift);
  write_json((std::filesystem::path(opt.out_dir) / "summary.json").string(), kv);
  if (res.status > 3) return res;  // interrupted: the summary says so, nothing more to say
  if (!opt.quiet && res.status == 0)
    spdlog::info("finished: {} steps in {:.2f} s ({:.3g} block-steps/s), fracture degree {:.4f}, "
                 "energy error {:.2e}; results in {}",
                 res.steps, res.wall_time_s, m.n_blocks() * static_cast<double>(res.steps - k0) / loop_this,
                 fd.area, last.error, opt.out_dir);
  return res;
}

}  // namespace cdem
