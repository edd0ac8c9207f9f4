// Whole-step throughput benchmark (`cdemblast bench`) and the reproducible benchmark models it
// shares with the kernel benchmarks (bench/bench_kernels.cpp). Results and method:
// docs/performance.md.
//
// run_bench builds a structured 3D tetrahedral box of about `blocks` blocks (cubes split into 6
// tets, no Gmsh, so every machine gets the same model), with granite-like rock, brittle
// Mohr-Coulomb interfaces and one bar charge along the vertical axis; it steps the model until
// spring points are breaking, then times `steps` steps of a loop that calls the kernels of
// Simulation::step in the same order, each timed with omp_get_wtime. It reports block-steps/s,
// spring-point-steps/s, ns per block-step, the split by kernel, memory per block, the 1 -> 2
// thread speed-up, a STREAM-like triad bandwidth measured in the same run and the fraction of it
// the step reaches (from an estimate of the bytes the kernels touch per step).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "cdem/io/case.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/model/materials.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

struct BenchOptions {
  std::int64_t blocks = 30000;  // target block count (the structured box gets close to it)
  int steps = 200;              // timed steps per run
  int threads = 0;              // threads of the main figures; 0: omp_get_max_threads()
                                // (OMP_NUM_THREADS when set)
  bool json = false;            // one JSON object on stdout instead of the text report
  double warmup_broken = 0.005;  // warm up until this fraction of the spring points is broken
                                 // (a larger one times a later, more cracked blast state)
  bool contact = true;           // general contact, on as in a case that can break
  bool fragmented = false;       // after the warm-up the broken points are released: the
                                 // blocks between the cracks are fragments touching through
                                 // contact (with warmup_broken: how fragmented)
  InterfaceLaw law = InterfaceLaw::MohrCoulomb;  // the box's interface law (--law)
  std::string interfaces;        // "tied" | "springs" (--interfaces); "": tied for the box, the
                                 // case's own for --case
  // --case FILE: time that case (its --set overrides applied) instead of the box: set-up timed
  // by part, then `warmup_steps` untimed steps (or the state of a run's newest checkpoint,
  // --from DIR, the same case: a late, fragmented state), then the timed steps
  std::string case_path;
  std::vector<std::string> sets;
  std::string from_run;
  std::int64_t warmup_steps = 0;
  // --partition: the scale projection (solver/bench_partition.cpp, docs/parallel.md) instead of
  // the timing: the box at each of `partition_blocks` (default: `blocks`) set up as a mesh and
  // its block graph only, partitioned by METIS into each of `partition_parts`; the cost per
  // block-step on one core `step_ns` (0: measured on the 30k box first)
  std::vector<int> partition_parts;
  std::vector<std::int64_t> partition_blocks;
  double step_ns = 0;
};

// The scale projection (--partition). Returns 0, or 1 without METIS.
int run_partition_projection(const BenchOptions& opt);

// Runs the benchmark and prints its report on stdout. Returns 0.
int run_bench(const BenchOptions& opt);

// Writes the bench box (opt.blocks, opt.law, opt.interfaces, opt.contact) as a case that `run`
// takes, so that it can be run as a whole process (under mpirun too): `dir`/bench.msh (MSH 4.1)
// and `dir`/case.toml (every key written; 0.2 ms of its bar's blast, 3 field outputs). Returns 0.
int export_bench_case(const BenchOptions& opt, const std::string& dir);

namespace bench {

// ---- reproducible structured models (no Gmsh) ----

// nx x ny x nz cubes of edge h from the origin, each split into the 6 tets of the Kuhn
// (Freudenthal) triangulation (tet p = (000, e_p0, e_p0 + e_p1, 111) for each permutation p of
// the axes; odd permutations have nodes 1 and 2 swapped so every tet is positive). Conforming,
// every tet has volume h^3 / 6 and L_c = h. One region "rock"; face sets "left" "right" (x),
// "front" "back" (y), "bottom" "top" (z), as generate_mesh names them.
Mesh structured_tet_box(int nx, int ny, int nz, double h);
// nx x ny squares of edge h split into 2 counter-clockwise triangles along (i,j)-(i+1,j+1).
Mesh structured_tri_grid(int nx, int ny, double h);
// nx x ny squares of edge h as counter-clockwise quadrilaterals.
Mesh structured_quad_grid(int nx, int ny, double h);

// Cell counts for about `blocks` blocks: tets (6 per cube, near-cubic box), triangles (2 per
// square) and quads (1 per square).
std::array<int, 3> tet_cells_for(std::int64_t blocks);
std::array<int, 2> tri_cells_for(std::int64_t blocks);
std::array<int, 2> quad_cells_for(std::int64_t blocks);

// Granite-like rock of SPEC 5.3: rho 2681 kg/m^3, E 99.3 GPa, nu 0.28 (region "rock").
BlockMaterial rock_material();
// Default interface of the given law with the SPEC 5.3 strengths: f_t 8.11 MPa, c 20 MPa,
// phi 35 deg, psi 15 deg, G_t 70 Pa.m, G_s 700 Pa.m, alpha 10.
InterfaceMaterial interface_material(InterfaceLaw law);

// A Case for in-code runs of a structured box model of cell size h spanning [0, extent]: the
// materials above, the built-in emulsion, `bars` vertical bar charges of 40 mm diameter (one at
// the centre for bars = 1, else spread on a circle of radius extent / 4), each from 0.75 of the
// height below the top, charged over its lower 2/3 (the rest is stemming) and initiated at the
// bottom at t = 0; 3D: bottom fixed and the four sides non-reflecting, top free; 2D: bottom
// fixed, sides non-reflecting (bars along y).
Case box_case(int dim, Vec3 extent, double h, InterfaceLaw law, int bars);

// A deterministic "mid-blast" state: every mesh vertex gets a pseudo-random displacement of
// amplitude strain * h (so each block sees a different strain of order `strain`) on top of a
// rigid rotation by `rotation` rad about z through the box centre; coincident nodes share it,
// plus a per-node jitter of amplitude `jitter` m (opens/closes the spring points). Velocities:
// per-vertex pseudo-random of amplitude `speed` m/s plus a per-node jitter of `speed_jitter`.
void apply_bench_state(Model& m, double h, double strain, double rotation, double jitter,
                       double speed, double speed_jitter, std::uint64_t seed = 1);

// Mean number of Newton iterations polar_3d takes on the tetrahedra of the model in its current
// state (the co-rotational kernel's dominant cost); inverted tets are skipped.
double mean_polar_iterations(const Model& m);

// Bytes held by the model: capacity() x sizeof(element) of every vector in Model (the nested
// facet lists included; material names and other strings not).
std::size_t model_bytes(const Model& m);

// Estimate of the bytes the kernels of one step touch (see docs/performance.md): every array a
// kernel reads counts once with its full size, every array it writes once more, as if each
// kernel streamed its arrays from memory with perfect reuse inside the kernel and none between
// kernels. Small serial parts (boundary facets, constraints) are left out; the bar loads count
// the loaded blocks only. The spring-state arrays only the full spring update touches (not the
// fast path of intact linear spring points) count for the fraction of spring points that take
// it in the current state.
struct StepBytes {
  double positions = 0, blocks = 0, springs = 0, gather = 0, loads = 0, integrate = 0;
  double total() const { return positions + blocks + springs + gather + loads + integrate; }
};
StepBytes estimate_step_bytes(const Model& m, std::size_t loaded_blocks);

// STREAM-like triad a[i] = b[i] + s c[i] over three arrays of `n` doubles with `threads`
// OpenMP threads (first touch by the same threads); best of `reps`. Returns GB/s (1e9 B/s)
// counting 24 bytes per element (two reads, one write; write-allocate not counted, as STREAM).
double triad_bandwidth(std::size_t n, int threads, int reps);

// Peak double-precision throughput of this machine's cores: per thread 64 independent
// multiply-add chains (8 AVX-512 registers, enough to cover the FMA latency on both pipes) run
// from registers, no memory traffic; best of `reps`. Returns GFlop/s (an FMA counts 2).
double peak_gflops(int threads, int reps);

// Floating-point operations of the tet block kernel per block (block_forces.cpp, tet_chunk),
// counted from its source: a multiply-add 2, a division 1, abs, max and compares 0. F = Ds Dm^-1,
// det F and the orthogonality test: 101; the polar decomposition: 72 per Newton iteration (the
// inverse by cofactors 44, R <- (R + R^-T) / 2 19, the change 9); U = R^T F, the strain, Hooke's
// stress, P = R S, the nodal forces, the Cauchy stress and the strain energy: 243. The spring
// gather of the blocks with opened interfaces, in the same kernel, is not counted.
double tet_kernel_flops(double polar_iterations);

}  // namespace bench
}  // namespace cdem
