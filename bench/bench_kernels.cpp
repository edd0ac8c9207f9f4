// Google Benchmark of the hot-loop kernels (ARCHITECTURE "How the hot loop is written") on
// structured models of about 30 000 blocks (bench_models.hpp): the block kernels (tet, triangle,
// quad), the spring kernel under each interface law, the gather, the integration, the position
// update, the bar loads and the whole Simulation::step. Threads: OMP_NUM_THREADS (default: all).
// items_per_second counts blocks (block, node and step kernels) or spring points (spring
// kernels); the counter t_per_block is the wall time per block of the model, so the rows of one
// step add up to the time of a block-step. Wall time (UseRealTime): the kernels are parallel.
//
// Run (medians of 5):
//   OMP_NUM_THREADS=2 build/bin/cdem_bench --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true      (one command line)
// Results: docs/performance.md.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdint>
#include <vector>

#include "bench_models.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/io/case.hpp"
#include "cdem/physics/block_forces.hpp"
#include "cdem/physics/integrate.hpp"
#include "cdem/physics/springs.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {
namespace {

using bench_models::Shape;

// items per iteration, the per-block time counter and the thread count.
void finish(benchmark::State& state, std::int64_t items, std::size_t blocks) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * items);
  state.counters["t_per_block"] = benchmark::Counter(
      static_cast<double>(blocks),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["threads"] = omp_get_max_threads();
}

const BlockGroup& only_group(const Model& m) { return m.groups.front(); }

// ---- block kernels ----

// strain: the order of the block strains (0: the rigid rotation and the spring jitter only, block
// strains of order 1e-6); the Newton iterations of the polar decomposition grow with it (counter
// polar_iters).
void BM_BlockForcesTet(benchmark::State& state, double strain) {
  Model m = bench_models::state_model(Shape::Tet, InterfaceLaw::MohrCoulomb, 0.2, 0.0, strain);
  const auto& g = only_group(m);
  for (auto _ : state) benchmark::DoNotOptimize(block_forces_tet(m, g.begin, g.end, nullptr));
  finish(state, g.end - g.begin, m.n_blocks());
  state.counters["polar_iters"] = bench::mean_polar_iterations(m);
}

void BM_BlockForcesTri(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Tri, InterfaceLaw::MohrCoulomb, 0.2, 0.0);
  const auto& g = only_group(m);
  for (auto _ : state) benchmark::DoNotOptimize(block_forces_tri(m, g.begin, g.end, nullptr));
  finish(state, g.end - g.begin, m.n_blocks());
}

void BM_BlockForcesQuad(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Quad, InterfaceLaw::MohrCoulomb, 0.2, 0.0);
  const auto& g = only_group(m);
  for (auto _ : state) benchmark::DoNotOptimize(block_forces_quad(m, g.begin, g.end, nullptr));
  finish(state, g.end - g.begin, m.n_blocks());
}

// ---- spring kernel, one law per benchmark ----
// jitter_dt: spring points opened/closed by up to this fraction of the tensile opening per node
// and direction; broken: every spring point starts broken (contact and friction only). The
// spring state is restored before every iteration (untimed), so each iteration does the same
// work. reference: the one-spring-point-at-a-time form (spring_forces_reference) instead of the
// vectorised kernel, for the ratio of the two in the same run.
void BM_SpringForces(benchmark::State& state, Shape shape, InterfaceLaw law, double jitter_dt,
                     bool broken, bool reference = false) {
  Model m = bench_models::state_model(shape, law, jitter_dt, 0.05);
  if (broken)
    for (std::size_t s = 0; s < m.n_springs(); ++s) {
      m.sp_state[s] = kBroken;
      m.sp_mode[s] = kModeTension;
    }
  const double dt = bench_models::stable_dt(m);
  const bench_models::SpringState saved(m);
  for (auto _ : state) {
    state.PauseTiming();
    saved.restore(m);
    state.ResumeTiming();
    if (reference)
      spring_forces_reference(m, dt, 1e-3);
    else
      spring_forces(m, dt, 1e-3);
  }
  finish(state, static_cast<std::int64_t>(m.n_springs()), m.n_blocks());
  // The mix of law branches the iterations went through.
  double broke = 0, soft = 0, contact = 0;
  for (std::size_t s = 0; s < m.n_springs(); ++s) {
    broke += m.sp_state[s] != kIntact;
    soft += m.sp_state[s] == kIntact && !m.sp_w.empty() && (m.sp_w[s] > 0 || m.sp_slip[s] > 0);
    contact += m.sp_state[s] == kBroken && m.sp_fn[s] < 0;
  }
  const double ns = static_cast<double>(m.n_springs());
  state.counters["broken"] = broke / ns;
  state.counters["softening"] = soft / ns;
  state.counters["in_contact"] = contact / ns;
}

// ---- node kernels ----

void BM_GatherSpringForces(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Tet, InterfaceLaw::MohrCoulomb, 0.2, 0.05);
  spring_forces(m, bench_models::stable_dt(m), 0.0);
  for (auto _ : state) gather_spring_forces(m);
  finish(state, static_cast<std::int64_t>(m.n_blocks()), m.n_blocks());
  state.counters["spring_points"] = static_cast<double>(m.n_springs());
}

void BM_Integrate(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Tet, InterfaceLaw::MohrCoulomb, 0.2, 0.05);
  block_forces(m, nullptr);
  release_zero_damping(m);  // as Simulation does: the bench rock is undamped
  const double dt = bench_models::stable_dt(m);
  std::vector<double> dissipated(m.n_blocks(), 0.0);
  for (auto _ : state) integrate(m, Vec3{0, 0, -9.81}, dt, dissipated.data(), nullptr);
  finish(state, static_cast<std::int64_t>(m.n_blocks()), m.n_blocks());
}

void BM_UpdatePositions(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Tet, InterfaceLaw::MohrCoulomb, 0.2, 0.05);
  const double dt = bench_models::stable_dt(m);
  for (auto _ : state) update_positions(m, dt);
  finish(state, static_cast<std::int64_t>(m.n_blocks()), m.n_blocks());
}

// ---- bar loads: 4 vertical bars on a circle of radius L/4, all segments ignited ----

void BM_BarLoads(benchmark::State& state) {
  Model m = bench_models::state_model(Shape::Tet, InterfaceLaw::MohrCoulomb, 0.2, 0.05);
  block_forces(m, nullptr);  // volume ratios for eq. 9
  const Case c = bench::box_case(3, bench_models::extent_of(bench_models::make_mesh(Shape::Tet)),
                                 bench_models::kH, InterfaceLaw::MohrCoulomb, 4);
  BarCharges bars = build_bar_charges(m, charge_spec(c));
  AppliedLoads out;
  for (auto _ : state) {
    out.clear();
    bar_loads(m, bars, out, 1.0);
  }
  finish(state, static_cast<std::int64_t>(bars.elem_block.size()), m.n_blocks());
  state.counters["segments"] = static_cast<double>(bars.n_segments());
  state.counters["loaded_blocks"] = static_cast<double>(bars.elem_block.size());
}

// ---- the whole step: one bar charge at the centre, from rest, bottom fixed, sides
// non-reflecting (the model of `cdemblast bench`, at 30k blocks) ----

void BM_SimulationStep(benchmark::State& state, Shape shape) {
  const Mesh mesh = bench_models::make_mesh(shape);
  const Case c = bench::box_case(shape == Shape::Tet ? 3 : 2, bench_models::extent_of(mesh),
                                 bench_models::kH, InterfaceLaw::MohrCoulomb, 1);
  // As `cdemblast run` sets a case up (prepare_case): the blocks holding the bar's charge get
  // their charge share before the simulation, and the bar bounds the time step.
  Model model = bench_models::base_model(shape);
  BarCharges bars = build_bar_charges(model, charge_spec(c));
  const double dt_bar = make_charge_cavities(model, bars);
  Simulation sim(std::move(model), c);
  sim.limit_dt(dt_bar, "blocks holding bar charges");
  sim.add_load([&bars](Model& mm, AppliedLoads& out, double t) { bar_loads(mm, bars, out, t); });
  for (auto _ : state) sim.step();
  const Model& m = sim.model();
  finish(state, static_cast<std::int64_t>(m.n_blocks()), m.n_blocks());
  state.counters["spring_points_per_s"] = benchmark::Counter(
      static_cast<double>(m.n_springs()), benchmark::Counter::kIsIterationInvariantRate);
  std::int64_t broken = 0;
  for (auto s : m.sp_state) broken += s != kIntact;
  state.counters["broken_at_end"] =
      static_cast<double>(broken) / static_cast<double>(m.n_springs());
}

BENCHMARK_CAPTURE(BM_BlockForcesTet, mid_strain, 5e-4)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BlockForcesTet, near_rigid, 0.0)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BlockForcesTet, high_strain, 5e-3)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BlockForcesTri)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BlockForcesQuad)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_elastic, Shape::Tet, InterfaceLaw::Elastic, 0.5, false)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_mohr_coulomb_intact, Shape::Tet, InterfaceLaw::MohrCoulomb,
                  0.2, false)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_fracture_energy, Shape::Tet, InterfaceLaw::FractureEnergy,
                  1.0, false)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_broken_contact, Shape::Tet, InterfaceLaw::MohrCoulomb, 1.0,
                  true)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_mohr_coulomb_intact_reference, Shape::Tet,
                  InterfaceLaw::MohrCoulomb, 0.2, false, true)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tet_broken_contact_reference, Shape::Tet,
                  InterfaceLaw::MohrCoulomb, 1.0, true, true)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SpringForces, tri_mohr_coulomb_intact, Shape::Tri, InterfaceLaw::MohrCoulomb,
                  0.2, false)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GatherSpringForces)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Integrate)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdatePositions)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BarLoads)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SimulationStep, tet, Shape::Tet)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SimulationStep, quad, Shape::Quad)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cdem
