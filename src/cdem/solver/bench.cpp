#include "cdem/solver/bench.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include "cdem/core/polar.hpp"
#include "cdem/physics/polar_tet.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/explosive_library.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/physics/block_forces.hpp"
#include "cdem/mesh/structured.hpp"
#include "cdem/solver/run.hpp"
#include "cdem/physics/boundaries.hpp"
#include "cdem/physics/integrate.hpp"
#include "cdem/physics/springs.hpp"
#include "cdem/physics/ties.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {
namespace bench {
namespace {

// splitmix64: a deterministic hash for the pseudo-random benchmark state.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
// Uniform in [-1, 1).
double unit(std::uint64_t key) {
  return 2.0 * static_cast<double>(mix(key) >> 11) * (1.0 / 9007199254740992.0) - 1.0;
}
Vec3 random_vec(std::uint64_t key, int dim) {
  return {unit(4 * key), unit(4 * key + 1), dim == 3 ? unit(4 * key + 2) : 0.0};
}

template <class T>
std::size_t bytes_of(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}
template <class T>
double size_of(const std::vector<T>& v) {
  return static_cast<double>(v.size() * sizeof(T));
}

}  // namespace

Mesh structured_tet_box(int nx, int ny, int nz, double h) {
  return cdem::structured_tet_box(nx, ny, nz, {h * nx, h * ny, h * nz});
}

Mesh structured_tri_grid(int nx, int ny, double h) { return structured_grid_2d(nx, ny, h, false); }
Mesh structured_quad_grid(int nx, int ny, double h) { return structured_grid_2d(nx, ny, h, true); }

std::array<int, 3> tet_cells_for(std::int64_t blocks) {
  const double cubes = std::max(1.0, static_cast<double>(blocks) / 6.0);
  const int n = std::max(1, static_cast<int>(std::lround(std::cbrt(cubes))));
  const int nz = std::max(1, static_cast<int>(std::lround(cubes / (double(n) * n))));
  return {n, n, nz};
}
std::array<int, 2> tri_cells_for(std::int64_t blocks) {
  const double sq = std::max(1.0, static_cast<double>(blocks) / 2.0);
  const int n = std::max(1, static_cast<int>(std::lround(std::sqrt(sq))));
  return {n, std::max(1, static_cast<int>(std::lround(sq / n)))};
}
std::array<int, 2> quad_cells_for(std::int64_t blocks) {
  const double sq = std::max(1.0, static_cast<double>(blocks));
  const int n = std::max(1, static_cast<int>(std::lround(std::sqrt(sq))));
  return {n, std::max(1, static_cast<int>(std::lround(sq / n)))};
}

BlockMaterial rock_material() {
  BlockMaterial m;
  m.name = "granite";
  m.density = 2681;
  m.youngs = 99.3e9;
  m.poisson = 0.28;
  m.regions = {"rock"};
  return m;
}

InterfaceMaterial interface_material(InterfaceLaw law) {
  InterfaceMaterial im;
  im.name = std::string("bond_") + name_of(law);
  im.law = law;
  im.tensile_strength = 8.11e6;
  im.cohesion = 20e6;
  im.friction_deg = 35;
  im.dilation_deg = 15;
  im.gt = 70;
  im.gs = 700;
  im.stiffness_factor = 10;
  im.is_default = true;
  return im;
}

Case box_case(int dim, Vec3 extent, double h, InterfaceLaw law, int bars) {
  Case c;
  c.path = "bench model";
  c.title = "bench";
  c.materials = {rock_material()};
  c.interfaces = {interface_material(law)};
  c.explosives = {{"emulsion", *builtin_explosive("emulsion")}};
  const int up_axis = dim == 3 ? 2 : 1;
  Vec3 up{};
  up[up_axis] = 1.0;
  const double height = extent[up_axis];
  // Off the cell lines by a fraction of a cell, so that no bar runs exactly along a face.
  const Vec3 centre = 0.5 * extent + Vec3{0.23 * h, dim == 3 ? 0.31 * h : 0.0, 0.0};
  for (int k = 0; k < bars; ++k) {
    Vec3 p = centre;
    if (bars > 1) {
      const double a = 2.0 * 3.14159265358979323846 * k / bars;
      if (dim == 3) {
        p.x += 0.25 * extent.x * std::cos(a);
        p.y += 0.25 * extent.y * std::sin(a);
      } else {
        p.x += 0.25 * extent.x * (2.0 * k / (bars - 1) - 1.0);
      }
    }
    HoleDef hole;
    hole.name = fmt::format("hole{}", k + 1);
    hole.collar = p;
    hole.collar[up_axis] = height;
    hole.end = p;
    hole.end[up_axis] = 0.25 * height;
    hole.diameter = 0.04;
    hole.model = ChargeModel::Bar;
    Deck d;
    d.explosive = "emulsion";
    d.length = 0.5 * height;
    d.bottom = hole.end;
    d.top = hole.end + d.length * up;
    hole.decks = {d};
    hole.stemming = {{d.length, 0.75 * height}};
    c.holes.push_back(hole);
  }
  BoundaryCondition fixed;
  fixed.faces = "bottom";
  fixed.type = BoundaryType::Fixed;
  c.boundaries.push_back(fixed);
  for (const char* side : {"left", "right", "front", "back"}) {
    if (dim == 2 && (std::string(side) == "front" || std::string(side) == "back")) continue;
    BoundaryCondition nr;
    nr.faces = side;
    nr.type = BoundaryType::NonReflecting;
    c.boundaries.push_back(nr);
  }
  return c;
}

void apply_bench_state(Model& m, double h, double strain, double rotation, double jitter,
                       double speed, double speed_jitter, std::uint64_t seed) {
  Vec3 lo = m.X(0), hi = m.X(0);
  for (const auto& p : m.X_nodes())
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  const Vec3 c = 0.5 * (lo + hi);
  const double cr = std::cos(rotation), sr = std::sin(rotation);
  const std::uint64_t vbase = mix(seed) & 0xffffffffULL, nbase = mix(seed + 1) << 32;
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    const auto vtx = static_cast<std::uint64_t>(m.node_vertex[n]);
    const Vec3 r = m.X(n) - c;
    const Vec3 rot{cr * r.x - sr * r.y, sr * r.x + cr * r.y, r.z};
    m.x[n] = c + rot + (strain * h) * random_vec(vbase + 2 * vtx, m.dim) +
             jitter * random_vec(nbase + 2 * n, m.dim);
    m.v[n] = speed * random_vec(vbase + 2 * vtx + 1, m.dim) +
             speed_jitter * random_vec(nbase + 2 * n + 1, m.dim);
  }
}

double mean_polar_iterations(const Model& m) {
  double sum = 0;
  std::int64_t count = 0;
  for (const auto& g : m.groups) {
    if (g.type != ElemType::Tet4 || g.kind != BlockKind::Elastic) continue;
    for (auto b = g.begin; b < g.end; ++b) {
      const auto n0 = m.block_first_node[b];
      const double* gm = m.geom.data() + m.geom_offset[b];
      Mat3 ds, dminv;
      for (int j = 0; j < 3; ++j) {
        const Vec3 d = m.x[n0 + 1 + j] - m.x[n0];
        ds(0, j) = d.x;
        ds(1, j) = d.y;
        ds(2, j) = d.z;
      }
      for (int q = 0; q < 9; ++q) dminv.m[q] = gm[q];
      Mat3 R;
      const int it = polar_3d_tet(ds * dminv, R);
      if (it < 0) continue;
      sum += it;
      ++count;
    }
  }
  return count ? sum / static_cast<double>(count) : 0.0;
}

std::size_t model_bytes(const Model& m) {
  // Every std::vector member of Model (keep in step with model/model.hpp).
  std::size_t b = 0;
  b += bytes_of(m.vertex_X) + bytes_of(m.x) + bytes_of(m.v) + bytes_of(m.f) + bytes_of(m.mass) +
       bytes_of(m.inv_mass) + bytes_of(m.damping) + bytes_of(m.local_damping) +
       bytes_of(m.node_vertex);
  b += bytes_of(m.groups) + bytes_of(m.block_type) + bytes_of(m.block_first_node) +
       bytes_of(m.block_region) + bytes_of(m.block_material) + bytes_of(m.block_elem_tag) +
       bytes_of(m.block_volume0) + bytes_of(m.block_size) + bytes_of(m.block_altitude0) +
       bytes_of(m.geom) + bytes_of(m.geom_offset) + bytes_of(m.stress) + bytes_of(m.stress0) +
       bytes_of(m.strain_energy) + bytes_of(m.vol_ratio);
  b += bytes_of(m.iface_block_a) + bytes_of(m.iface_block_b) + bytes_of(m.iface_material) +
       bytes_of(m.iface_normal) + bytes_of(m.sp_a) + bytes_of(m.sp_b) + bytes_of(m.sp_area.v) +
       bytes_of(m.sp_kn.v) + bytes_of(m.sp_ks.v) + bytes_of(m.sp_fn) + bytes_of(m.sp_fs) +
       bytes_of(m.sp_w) + bytes_of(m.sp_slip) + bytes_of(m.sp_dil) + bytes_of(m.sp_g0) +
       bytes_of(m.sp_state) + bytes_of(m.sp_mode) + bytes_of(m.sp_break_time) +
       bytes_of(m.sp_dissipated) + bytes_of(m.block_iface_offset) + bytes_of(m.block_iface_list);
  // the tied mode's clusters and lists
  b += bytes_of(m.sp_tied) + bytes_of(m.vtx_offset) + bytes_of(m.vtx_nodes) + bytes_of(m.vtx_run) +
       bytes_of(m.iface_check) + bytes_of(m.iface_active) + bytes_of(m.active_ifaces) +
       bytes_of(m.active_merge) +
       bytes_of(m.block_active) + bytes_of(m.vtx_scratch) + bytes_of(m.tie_reject) +
       bytes_of(m.mat_lambda) + bytes_of(m.mat_shear);
  b += bytes_of(m.block_materials) + bytes_of(m.iface_materials) + bytes_of(m.spring_laws) +
       bytes_of(m.region_names) + bytes_of(m.facet_sets);
  for (const auto& s : m.facet_sets) b += bytes_of(s.facets);
  return b;
}

StepBytes estimate_step_bytes(const Model& m, std::size_t loaded_blocks) {
  StepBytes s;
  // update_positions: read x, v; write x.
  s.positions = 2 * size_of(m.x) + size_of(m.v);
  // block_forces: read the block arrays, x and the reference gradients; write f, stress, strain
  // energy, volume ratio.
  s.blocks = size_of(m.block_first_node) + size_of(m.geom_offset) + size_of(m.geom) +
             size_of(m.block_material) + size_of(m.x) + size_of(m.stress0) +
             size_of(m.block_volume0) + size_of(m.f) + size_of(m.stress) +
             size_of(m.strain_energy) + size_of(m.vol_ratio);
  // spring_forces: read the interface arrays, block sizes, node indices, x, v and the spring
  // constants. Spring state: the fast path (intact spring points under a linear law) reads
  // state, F_s, k_n, k_s, A_c and writes F_n, F_s; the full update (broken, fracture-energy) also
  // reads F_n, w, slip, dilation, mode, break time and dissipation and writes them back. Their bytes count for the fraction of spring points that take it.
  double slow = 0;
  for (std::size_t sp = 0; sp < m.n_springs(); ++sp)
    slow += m.sp_state[sp] != kIntact ||
            m.spring_laws[m.iface_material[sp / m.springs_per_iface]].law ==
                InterfaceLaw::FractureEnergy;
  const double slow_fraction = m.n_springs() ? slow / static_cast<double>(m.n_springs()) : 0.0;
  s.springs = size_of(m.iface_material) + size_of(m.iface_block_a) + size_of(m.iface_block_b) +
              size_of(m.block_size) + size_of(m.sp_a) + size_of(m.sp_b) + size_of(m.x) +
              size_of(m.v) + size_of(m.sp_kn.v) + size_of(m.sp_ks.v) + size_of(m.sp_area.v) +
              size_of(m.sp_g0) + size_of(m.sp_state) + 2 * size_of(m.sp_fs) + size_of(m.sp_fn) +
              2 * size_of(m.iface_normal) +
              slow_fraction *
                  (size_of(m.sp_fn) + size_of(m.sp_state) +
                   2 * (size_of(m.sp_w) + size_of(m.sp_slip) + size_of(m.sp_dil) +
                        size_of(m.sp_mode) + size_of(m.sp_break_time) + size_of(m.sp_dissipated)));
  // The spring gather (inside block_forces): read the block -> interface CSR, the interface
  // normals, the node indices and F_n, F_s of every spring point twice (once from each side);
  // f is already in cache from the block kernel.
  s.gather = size_of(m.block_iface_offset) + size_of(m.block_iface_list) +
             2 * (size_of(m.iface_normal) + size_of(m.sp_fn) + size_of(m.sp_fs)) +
             size_of(m.sp_a) + size_of(m.sp_b);
  // bar loads: per loaded block, read x of its 4 nodes, read and write f, and the AppliedLoads
  // record (node, force, old velocity) per node.
  s.loads = static_cast<double>(loaded_blocks) * 4.0 *
            (3 * sizeof(Vec3) + sizeof(std::int32_t) + 2 * sizeof(Vec3) + sizeof(Vec3));
  // integrate: read mass, f, v, local damping, damping, dissipated; write v, dissipated (the
  // damping arrays and the dissipation only when the model has damping: see integrate.hpp).
  const bool damped = !m.damping.empty() || !m.local_damping.empty();
  s.integrate = size_of(m.mass) + size_of(m.f) + 2 * size_of(m.v) + size_of(m.local_damping) +
                size_of(m.damping) +
                (damped ? 2.0 * static_cast<double>(m.n_nodes() * sizeof(double)) : 0.0);
  return s;
}

double triad_bandwidth(std::size_t n, int threads, int reps) {
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  double* pa = a.get();
  double* pb = b.get();
  double* pc = c.get();
  const auto nn = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::int64_t i = 0; i < nn; ++i) {
    pa[i] = 0.0;
    pb[i] = 1.0;
    pc[i] = 2.0;
  }
  double best = 1e300;
  const double s = 3.0;
  for (int r = 0; r < reps; ++r) {
    const double t0 = omp_get_wtime();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::int64_t i = 0; i < nn; ++i) pa[i] = pb[i] + s * pc[i];
    best = std::min(best, omp_get_wtime() - t0);
  }
  // Keep the result observable so the loop cannot be dropped.
  volatile double sink = pa[n / 2];
  (void)sink;
  return 24.0 * static_cast<double>(n) / best / 1e9;
}

double peak_gflops(int threads, int reps) {
  constexpr int kAcc = 64;
  double sum = 0;
  auto run = [&](std::int64_t iters) {
    const double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads) reduction(+ : sum)
    {
      alignas(64) double acc[kAcc];
      for (int i = 0; i < kAcc; ++i) acc[i] = 1.0 + 1e-3 * i;
      // a x + b with |a| < 1: every chain stays bounded (fixed point b / (1 - a) = 0.1)
      const double a = 0.999999, b = 1e-7;
      for (std::int64_t it = 0; it < iters; ++it) {
#pragma omp simd
        for (int i = 0; i < kAcc; ++i) acc[i] = std::fma(acc[i], a, b);
      }
      for (int i = 0; i < kAcc; ++i) sum += acc[i];
    }
    return omp_get_wtime() - t0;
  };
  // the count that takes at least 20 ms (about 20 million on this machine; far fewer in a
  // debug or sanitizer build, which the tests run), then the best of `reps` runs of it
  std::int64_t iters = 10'000;
  double best = run(iters);
  while (best < 0.02 && iters < (std::int64_t{1} << 40)) best = run(iters *= 2);
  for (int r = 1; r < reps; ++r) best = std::min(best, run(iters));
  volatile double sink = sum;  // (the chains' results observed: the loops cannot be dropped)
  (void)sink;
  return 2.0 * kAcc * static_cast<double>(iters) * threads / best / 1e9;
}

double tet_kernel_flops(double polar_iterations) { return 344.0 + 72.0 * polar_iterations; }

}  // namespace bench

namespace {

constexpr int kNumKernels = kNumStepKernels;
constexpr const char* const* kKernelNames = kStepKernelNames;

struct LoopResult {
  int threads = 0;
  double wall = 0;                      // s, whole loop
  double cpu = 0;                       // s, CPU time of the process over the loop
  std::array<double, kNumKernels> k{};  // s per kernel, summed over the steps
  std::int64_t broken_end = 0;
  std::int64_t inverted = 0;  // inverted blocks summed over the steps (expected 0)
  double work = 0;            // boundary + explosive work, absorbed energy (J)
  std::int64_t pairs = 0, active_max = 0, rebuilds = 0;  // contact at the end: candidate pairs,
                                                         // most in contact, rebuilds in the loop
  int settle = 0;  // untimed steps to the copy's first contact rebuild
  // the share of the pairs tested per step (node-block, block pairs; the rest asleep)
  double tested = 0, block_pairs_tested = 0;
};

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The 1-minute load average (/proc/loadavg), or -1.
double load_average() {
  double l = -1;
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}

// The fragmented state (--fragmented): every spring point the warm-up broke is released, its
// force zero, so the blocks between the cracks are fragments that touch only through general
// contact (in a run a broken point is released once its pair has separated by half a block;
// here at once, with the faces still touching: the densest contact state cracking can make).
std::int64_t release_broken(Model& m) {
  std::int64_t n = 0;
  for (std::size_t s = 0; s < m.n_springs(); ++s) {
    if (m.sp_state[s] != kBroken) continue;
    if (m.tied && m.sp_tied[s]) untie_point(m, s);
    m.sp_state[s] = kReleased;
    m.sp_fn[s] = 0;
    m.sp_fs[s] = Vec3{};
    ++n;
  }
  m.released_points += n;
  return n;
}

std::int64_t broken_springs(const Model& m) {
  std::int64_t n = 0;
  for (auto s : m.sp_state) n += s != kIntact;
  return n;
}

// `steps` steps of Simulation::step from a copy of the prepared state, each kernel timed
// (Simulation::set_timer).
LoopResult timed_loop(const PreparedCase& snapshot, int steps, int threads) {
  omp_set_num_threads(threads);
  PreparedCase pc = snapshot;
  pc.sim.clear_loads();
  add_charge_loads(pc);  // bound to this copy's charges
  LoopResult r;
  r.threads = threads;
  StepTimes times;
  // Two untimed steps: first touch of the copies by this thread count, warm caches.
  pc.sim.step();
  pc.sim.step();
  // Then untimed steps up to the copy's first contact rebuild (at most `steps`): a copied state's
  // contact arrays have their exact sizes, so its first rebuild grows them and touches new pages,
  // once in a run (about 100 ms in the late SPEC 5.3 state, a third of a millisecond on each of
  // 300 timed steps), not the steady state timed here.
  if (pc.sim.contact().enabled && !pc.sim.contact().pair_node.empty()) {
    const std::int64_t rb = pc.sim.contact().rebuilds;
    while (r.settle < steps && pc.sim.contact().rebuilds == rb) {
      pc.sim.step();
      ++r.settle;
    }
  }
  pc.sim.set_timer(&times);
  const std::int64_t rebuilds0 = pc.sim.contact().rebuilds;
  const std::int64_t tests0 = pc.sim.contact().pair_tests, btests0 = pc.sim.contact().block_pair_tests;
  const double w0 = omp_get_wtime(), cpu0 = process_cpu_seconds();
  for (int s = 0; s < steps; ++s) {
    pc.sim.step();
    r.inverted += pc.sim.inverted_blocks();
  }
  r.wall = omp_get_wtime() - w0;
  r.cpu = process_cpu_seconds() - cpu0;
  r.k = times.s;
  r.broken_end = broken_springs(pc.sim.model());
  const ContactSet& cs = pc.sim.contact();
  r.pairs = static_cast<std::int64_t>(cs.pair_node.size());
  r.active_max = cs.active_max;
  r.rebuilds = cs.rebuilds - rebuilds0;
  if (r.pairs > 0)
    r.tested = static_cast<double>(cs.pair_tests - tests0) / (static_cast<double>(r.pairs) * steps);
  if (!cs.bp_a.empty())
    r.block_pairs_tested = static_cast<double>(cs.block_pair_tests - btests0) /
                           (static_cast<double>(cs.bp_a.size()) * steps);
  return r;
}

// Best (smallest wall time) of `reps` runs.
LoopResult best_loop(const PreparedCase& snapshot, int steps, int threads, int reps) {
  LoopResult best;
  for (int i = 0; i < reps; ++i) {
    LoopResult r = timed_loop(snapshot, steps, threads);
    if (i == 0 || r.wall < best.wall) best = r;
  }
  return best;
}

}  // namespace

int export_bench_case(const BenchOptions& opt, const std::string& dir) {
  const double h = 0.05;
  const auto cells = bench::tet_cells_for(std::max<std::int64_t>(6, opt.blocks));
  const Vec3 extent{h * cells[0], h * cells[1], h * cells[2]};
  Case c = bench::box_case(3, extent, h, opt.law, 1);
  c.title = "bench_box";
  c.contact.enabled = opt.contact;
  if (opt.interfaces == "springs") c.interface_mode = InterfaceMode::Springs;
  c.end_time = 2e-4;
  c.output_times = {1e-4};
  c.history_interval = 2e-6;
  std::filesystem::create_directories(dir);
  const auto msh = std::filesystem::path(dir) / "bench.msh";
  write_gmsh(bench::structured_tet_box(cells[0], cells[1], cells[2], h), msh.string());
  c.mesh_file = "bench.msh";  // (relative to the case file)
  c.path = "cdemblast bench --export";
  const auto toml = std::filesystem::path(dir) / "case.toml";
  std::FILE* f = std::fopen(toml.string().c_str(), "w");
  if (!f) throw std::runtime_error(fmt::format("bench --export: cannot write '{}'", toml.string()));
  const std::string text = resolved_case_toml(c);
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error(fmt::format("bench --export: cannot write '{}'", toml.string()));
  load_case(toml.string(), {});  // it must read back as a valid case (throws if not)
  fmt::print("bench box: {} tetrahedra, written as {} and {}; run it with\n  cdemblast run {}\n",
             6LL * cells[0] * cells[1] * cells[2], toml.string(), msh.string(), toml.string());
  return 0;
}

int run_bench(const BenchOptions& opt) {
  const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();
  const int steps = std::max(1, opt.steps);
  const bool own_case = !opt.case_path.empty();
  // The model: the structured box (reproducible on every machine, no Gmsh), or the user's case.
  const double h = 0.05;
  const auto cells = bench::tet_cells_for(std::max<std::int64_t>(6, opt.blocks));
  Case c;
  if (own_case) {
    std::vector<std::string> sets = opt.sets;
    if (!opt.interfaces.empty()) sets.push_back("simulation.interfaces=\"" + opt.interfaces + "\"");
    c = load_case(opt.case_path, sets);
    if (!opt.contact) c.contact.enabled = false;
  } else {
    const Vec3 extent{h * cells[0], h * cells[1], h * cells[2]};
    c = bench::box_case(3, extent, h, opt.law, 1);
    c.contact.enabled = opt.contact || opt.fragmented;
    if (opt.interfaces == "springs") c.interface_mode = InterfaceMode::Springs;
  }

  const double load0 = load_average();
  omp_set_num_threads(threads);
  double setup0 = omp_get_wtime();
  const Mesh mesh = own_case ? load_mesh(c) : bench::structured_tet_box(cells[0], cells[1], cells[2], h);
  const double mesh_s = omp_get_wtime() - setup0;
  omp_set_num_threads(threads);  // (meshing may have changed it)
  SetupTimes parts;
  PreparedCase pc = prepare_case(c, mesh, &parts);  // as `cdemblast run` sets a case up
  add_charge_loads(pc);
  Simulation& sim = pc.sim;
  const BarCharges& bars = pc.bars;
  const double setup_s = omp_get_wtime() - setup0;

  const Model& m0 = sim.model();
  const auto nb = static_cast<double>(m0.n_blocks());
  const auto nsp = static_cast<double>(m0.n_springs());
  const std::size_t mem = bench::model_bytes(m0);

  // Warm-up. The box: step until cracking is under way (--warmup-broken, default 0.5 % of the
  // spring points broken), at most 20 x steps + 2000 steps (x 10 beyond the default fraction).
  // A case: --warmup-steps steps, after the state of a run's checkpoint (--from) if given.
  const double warm0 = omp_get_wtime();
  std::int64_t warm_steps = 0, broken0 = 0, released = 0;
  if (own_case) {
    if (!opt.from_run.empty()) load_checkpointed_state(pc, c, opt.from_run);
    for (; warm_steps < opt.warmup_steps; ++warm_steps) sim.step();
  } else {
    const std::int64_t want_broken =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(opt.warmup_broken * nsp));
    const std::int64_t max_warm = (20LL * steps + 2000) * (opt.warmup_broken > 0.005 ? 10 : 1);
    // (a late fraction can take many minutes: progress on stderr every 30 s, so that a long
    // warm-up is not taken for a hang)
    double report_at = warm0 + 30.0;
    while (warm_steps < max_warm) {
      sim.step();
      ++warm_steps;
      if (warm_steps % 10 == 0 && (broken0 = broken_springs(sim.model())) >= want_broken) break;
      if (warm_steps % 10 == 0 && omp_get_wtime() > report_at) {
        report_at += 30.0;
        fmt::print(stderr,
                   "bench: warm-up {} of at most {} steps, {:.1f} s: {:.2f} % of the spring points "
                   "broken, {:.2f} % wanted\n",
                   warm_steps, max_warm, omp_get_wtime() - warm0,
                   100.0 * static_cast<double>(broken0) / nsp, 100.0 * opt.warmup_broken);
        std::fflush(stderr);
      }
    }
  }
  if (opt.fragmented) {
    released = release_broken(sim.model());
    sim.step();  // the contact pairs of the fragmented state are built in the warm-up
    ++warm_steps;
  }
  broken0 = broken_springs(sim.model());
  const double warm_s = omp_get_wtime() - warm0;

  // Timed runs, each from the same post-warm-up state: 1 and 2 threads (and `threads`).
  const Model& snapshot = sim.model();
  const double t0 = sim.time(), dt = sim.dt();
  const double polar_it = bench::mean_polar_iterations(snapshot);
  constexpr int kReps = 3;
  const LoopResult r1 = best_loop(pc, steps, 1, kReps);
  const LoopResult r2 = best_loop(pc, steps, 2, kReps);
  LoopResult rm = threads == 1 ? r1 : r2;
  if (threads != 1 && threads != 2) rm = best_loop(pc, steps, threads, kReps);

  // Memory bandwidth: triad over 3 x 80 MB, 2 threads, best of 5.
  const std::size_t triad_n = 10'000'000;
  const double triad = bench::triad_bandwidth(triad_n, 2, 5);
  // The same at the size of the model's arrays (3 arrays of model_bytes / 3 in all): the
  // bandwidth of the cache level the step's working set lives in.
  const std::size_t triad_ws_n = std::max<std::size_t>(1024, mem / (3 * sizeof(double)));
  const double triad_ws = bench::triad_bandwidth(triad_ws_n, 2, 20);
  // Roofline: the cores' peak against the intensity of the block kernel and of the step.
  const double peak = bench::peak_gflops(2, 5);
  omp_set_num_threads(threads);

  const auto bytes = bench::estimate_step_bytes(snapshot, bars.elem_block.size());
  const bool tets = std::all_of(snapshot.block_type.begin(), snapshot.block_type.end(),
                                [](ElemType t) { return t == ElemType::Tet4; });
  const double tet_flops = tets ? bench::tet_kernel_flops(polar_it) : 0.0;
  const double blk_bytes = (bytes.blocks + bytes.gather) / nb;          // B per block
  const double blk_ns = rm.k[kStepBlocks] / (nb * steps) * 1e9;        // ns per block-step
  const double blk_gflops = blk_ns > 0 ? tet_flops / blk_ns : 0.0;      // flop / ns = GFlop/s
  const double step_s = rm.wall / steps;
  const double ns_block = rm.wall / (nb * steps) * 1e9;
  const double block_rate = nb * steps / rm.wall;
  const double spring_rate = nsp * steps / rm.wall;
  const double speedup = r1.wall / r2.wall;
  const double step_gbs = bytes.total() / step_s / 1e9;
  const double solver_extra = static_cast<double>(sim.solver_bytes());
  const double contact_extra = static_cast<double>(contact_bytes(sim.contact()));
  const double load1 = load_average();
  // CPU time / (wall time x threads): below 1 when the process did not have its cores (a busy
  // machine); the 1-thread CPU time per block-step is then the more trustworthy cost figure.
  const double share1 = r1.cpu / r1.wall, share2 = r2.cpu / (2.0 * r2.wall);
  const double cpu_ns_block_1 = r1.cpu / (nb * steps) * 1e9;
  double ksum = 0;
  for (double k : rm.k) ksum += k;

  if (opt.json) {
    std::string kernels;
    for (int k = 0; k < kNumKernels; ++k)
      kernels += fmt::format(
          "{}\"{}\": {{\"ns_per_block_step\": {:.4g}, \"share\": {:.4f}, "
          "\"ns_per_block_step_1_thread\": {:.4g}}}",
          k ? ", " : "", kKernelNames[k], rm.k[k] / (nb * steps) * 1e9, rm.k[k] / ksum,
          r1.k[k] / (nb * steps) * 1e9);
    std::printf(
        "%s\n",
        fmt::format(
            "{{\"blocks\": {}, \"nodes\": {}, \"interfaces\": {}, \"spring_points\": {}, "
            "\"steps\": {}, \"threads\": {}, \"dt\": {:.6g}, \"warmup_steps\": {}, \"settle_steps\": {}, "
            "\"broken_at_start\": {}, \"broken_at_end\": {}, \"ns_per_block_step\": {:.4g}, "
            "\"block_steps_per_s\": {:.4g}, \"spring_steps_per_s\": {:.4g}, "
            "\"ns_per_block_step_1_thread\": {:.4g}, \"ns_per_block_step_2_threads\": {:.4g}, "
            "\"speedup_2_threads\": {:.4g}, "
            "\"bytes_per_block\": {:.1f}, \"bytes_per_block_with_solver\": {:.1f}, "
            "\"bytes_per_block_with_contact\": {:.1f}, "
            "\"triad_gb_s\": {:.4g}, \"triad_ws_gb_s\": {:.4g}, \"step_bytes_estimate\": {:.4g}, "
            "\"step_gb_s_estimate\": {:.4g}, \"bandwidth_fraction\": {:.4g}, "
            "\"bandwidth_fraction_ws\": {:.4g}, \"polar_iterations\": {:.3g}, "
            "\"peak_gflops\": {:.4g}, \"tet_flops_per_block\": {:.4g}, "
            "\"block_kernel_bytes_per_block\": {:.4g}, \"block_kernel_gflops\": {:.4g}, "
            "\"cpu_ns_per_block_step_1_thread\": {:.4g}, "
            "\"cpu_share_1_thread\": {:.3g}, \"cpu_share_2_threads\": {:.3g}, "
            "\"load_average\": [{:.2f}, {:.2f}], \"contact\": {}, \"released\": {}, "
            "\"contact_pairs\": {}, \"contact_active_max\": {}, \"contact_tested\": {:.4g}, "
            "\"contact_block_pairs_tested\": {:.4g}, \"interface_mode\": \"{}\", "
            "\"setup_s\": {{\"total\": {:.4g}, \"mesh\": {:.4g}, \"topology\": {:.4g}, "
            "\"charges\": {:.4g}, \"simulation\": {:.4g}}}, \"kernels\": {{{}}}}}",
            m0.n_blocks(), m0.n_nodes(), m0.n_ifaces(), m0.n_springs(), steps, threads, dt,
            warm_steps, rm.settle, broken0, rm.broken_end, ns_block, block_rate, spring_rate,
            r1.wall / (nb * steps) * 1e9, r2.wall / (nb * steps) * 1e9, speedup,
            static_cast<double>(mem) / nb, (static_cast<double>(mem) + solver_extra) / nb,
            (static_cast<double>(mem) + solver_extra + contact_extra) / nb, triad,
            triad_ws, bytes.total(), step_gbs, step_gbs / triad, step_gbs / triad_ws, polar_it,
            peak, tet_flops, blk_bytes, blk_gflops, cpu_ns_block_1, share1, share2, load0, load1, c.contact.enabled, released,
            rm.pairs, rm.active_max, rm.tested, rm.block_pairs_tested, m0.tied ? "tied" : "springs", setup_s, mesh_s, parts.topology,
            parts.charges, parts.simulation, kernels)
            .c_str());
    return 0;
  }

  std::string out;
  const char* mode = m0.tied ? "tied" : "springs";
  if (own_case) {
    out += fmt::format("cdemblast bench --case {}: {} blocks ({}D), {} nodes, {} interfaces, {} spring points\n",
                       opt.case_path, m0.n_blocks(), m0.dim, m0.n_nodes(), m0.n_ifaces(), m0.n_springs());
    std::string laws;
    for (const auto& im : m0.iface_materials) laws += fmt::format("{}{}", laws.empty() ? "" : ", ", name_of(im.law));
    out += fmt::format("  {} interfaces ({}); {} bar segments, {} loaded blocks; {} explosive blocks\n", mode,
                       laws, bars.n_segments(), bars.elem_block.size(), pc.solids.block.size());
    if (!opt.from_run.empty())
      out += fmt::format("  state: the newest checkpoint of '{}' (t = {:.4g} s, step {})\n", opt.from_run,
                         sim.time(), sim.steps() - warm_steps);
  } else {
    out += fmt::format(
        "cdemblast bench: {} tetrahedra ({} x {} x {} cubes of {} m, 6 tets each), {} nodes, {} "
        "interfaces, {} spring points\n",
        m0.n_blocks(), cells[0], cells[1], cells[2], h, m0.n_nodes(), m0.n_ifaces(), m0.n_springs());
    out += fmt::format(
        "  granite E 99.3 GPa, {} {} interfaces (f_t 8.11 MPa, c 20 MPa, phi 35 deg); one emulsion "
        "bar (40 mm, {} segments, {} loaded blocks); bottom fixed, sides non-reflecting\n",
        mode, name_of(opt.law), bars.n_segments(), bars.elem_block.size());
  }
  if (opt.fragmented)
    out += fmt::format(
        "  fragmented: the {} points broken in the warm-up are released (the blocks between the "
        "cracks are fragments)\n",
        released);
  if (c.contact.enabled)
    out += fmt::format(
        "  general contact: {} candidate pairs, at most {} in contact, {} rebuilds in the timed "
        "steps (timed from each copy's first rebuild on: {} untimed steps before); tested per "
        "step (the rest asleep): {:.1f} % of the node-block pairs, {:.1f} % of the block pairs\n",
        rm.pairs, rm.active_max, rm.rebuilds, rm.settle, 100 * rm.tested, 100 * rm.block_pairs_tested);
  else
    out += "  general contact off (--no-contact)\n";
  out += fmt::format(
      "  set-up {:.2f} s: mesh {:.2f} s, topology {:.2f} s, charges {:.2f} s, simulation {:.2f} s; "
      "dt = {:.4g} s ({})\n",
      setup_s, mesh_s, parts.topology, parts.charges, parts.simulation, dt, sim.stable().limit);
  out += fmt::format(
      "  warm-up: {} steps in {:.2f} s to t = {:.4g} s: {} spring points broken ({:.2f} %)\n",
      warm_steps, warm_s, t0, broken0, 100.0 * static_cast<double>(broken0) / nsp);
  if (m0.dim == 3)
    out += fmt::format(
        "  mean Newton iterations of the tet polar decomposition at that state: {:.2f}\n", polar_it);
  out += fmt::format(
      "  timed: {} steps per run, best of {} runs from the same state; {} broken "
      "at the end ({:.2f} %)\n\n",
      steps, kReps, rm.broken_end, 100.0 * static_cast<double>(rm.broken_end) / nsp);
  if (rm.inverted > 0)
    out +=
        fmt::format("  WARNING: {} inverted block-steps during the timed steps\n\n", rm.inverted);
  out += fmt::format("throughput ({} thread{}):\n", threads, threads == 1 ? "" : "s");
  out += fmt::format("  block-steps/s          {:.4g}\n", block_rate);
  out += fmt::format("  spring-point-steps/s   {:.4g}\n", spring_rate);
  out += fmt::format("  ns per block-step      {:.1f}{}\n", ns_block, own_case ? "" : "   (target 40 on 2 threads)");
  out += "\n";
  double ksum1 = 0;
  for (double k : r1.k) ksum1 += k;
  out += fmt::format("kernel split ({} thread{}; last column: the 1-thread run):\n", threads,
                     threads == 1 ? "" : "s");
  out += fmt::format("  {:<22} {:>9} {:>10} {:>7} {:>12}\n", "kernel", "ms/step", "ns/block",
                     "share", "1T ns/block");
  for (int k = 0; k < kNumKernels; ++k)
    out += fmt::format("  {:<22} {:>9.3f} {:>10.2f} {:>6.1f}% {:>12.2f}\n", kKernelNames[k],
                       rm.k[k] / steps * 1e3, rm.k[k] / (nb * steps) * 1e9, 100.0 * rm.k[k] / ksum,
                       r1.k[k] / (nb * steps) * 1e9);
  out += fmt::format("  {:<22} {:>9.3f} {:>10.2f} {:>7} {:>12.2f}\n\n", "sum", ksum / steps * 1e3,
                     ksum / (nb * steps) * 1e9, "", ksum1 / (nb * steps) * 1e9);
  out += fmt::format(
      "threads: 1 thread {:.1f} ns/block-step, 2 threads {:.1f}: speed-up {:.2f} (target >= "
      "1.8)\n",
      r1.wall / (nb * steps) * 1e9, r2.wall / (nb * steps) * 1e9, speedup);
  out += fmt::format(
      "  CPU time / (wall x threads): {:.2f} on 1 thread, {:.2f} on 2; 1-thread CPU time {:.1f} "
      "ns/block-step\n",
      share1, share2, cpu_ns_block_1);
  out += fmt::format("  load average {:.2f} at the start, {:.2f} at the end ({} cores)\n", load0,
                     load1, omp_get_num_procs());
  if (share1 < 0.9 || share2 < 0.9 || load1 > omp_get_num_procs())
    out +=
        "  WARNING: the machine is busy (other processes share the cores): wall times, the\n"
        "  speed-up and the bandwidth fraction are pessimistic; compare CPU times.\n";
  out += fmt::format(
      "memory: Model {:.0f} bytes per block, {:.0f} with the solver's per-node arrays, {:.0f} with "
      "general contact's (target <= 1024 in all)\n",
      static_cast<double>(mem) / nb, (static_cast<double>(mem) + solver_extra) / nb,
      (static_cast<double>(mem) + solver_extra + contact_extra) / nb);
  out += fmt::format(
      "bandwidth: triad a = b + s c, 3 x {:.0f} MB, 2 threads, best of 5: {:.2f} GB/s\n",
      triad_n * 8.0 / 1e6, triad);
  out += fmt::format("  the same over the model's size (3 x {:.1f} MB), best of 20: {:.2f} GB/s\n",
                     triad_ws_n * 8.0 / 1e6, triad_ws);
  out += fmt::format(
      "  step touches ~{:.1f} MB ({:.0f} B per block; estimate: each array a kernel reads or "
      "writes counted once per kernel)\n",
      bytes.total() / 1e6, bytes.total() / nb);
  out += fmt::format(
      "  -> {:.2f} GB/s at {} thread{} = {:.0f} % of the triad ({:.0f} % of the model-size "
      "triad); 1 thread: {:.2f} GB/s of CPU time\n",
      step_gbs, threads, threads == 1 ? "" : "s", 100.0 * step_gbs / triad,
      100.0 * step_gbs / triad_ws, bytes.total() * steps / r1.cpu / 1e9);
  out += fmt::format("roofline: peak multiply-add throughput, 2 threads, best of 5: {:.1f} GFlop/s; ridge "
                     "at {:.2f} flop/B against the triad\n", peak, peak / triad);
  if (tets) {
    const double ai = tet_flops / blk_bytes, roof = std::min(peak, ai * triad);
    out += fmt::format(
        "  block kernel: {:.0f} flop per block (counted from the source, {:.2f} Newton iterations), "
        "~{:.0f} B: {:.2f} flop/B; {:.2f} GFlop/s at {} thread{} = {:.0f} % of its roof "
        "({:.1f} GFlop/s, {}-bound)\n",
        tet_flops, polar_it, blk_bytes, ai, blk_gflops, threads, threads == 1 ? "" : "s",
        100.0 * blk_gflops / roof, roof, ai * triad < peak ? "bandwidth" : "compute");
    const double ai_step = tet_flops * nb / bytes.total();
    out += fmt::format(
        "  whole step: at least {:.0f} flop per block (the block kernel's alone) over {:.0f} B: >= "
        "{:.2f} flop/B, >= {:.2f} GFlop/s = >= {:.1f} % of the peak\n",
        tet_flops, bytes.total() / nb, ai_step, tet_flops / ns_block, 100.0 * tet_flops / ns_block / peak);
  }
  std::fputs(out.c_str(), stdout);
  return 0;
}

}  // namespace cdem
