// `cdemblast bench --partition`: the scale projection of issue 17 (docs/parallel.md). The bench
// box is generated at each size as a mesh, its block graph built from the shared faces (no
// model: a 10M-block model would not fit this machine's memory), partitioned by METIS, and each
// partition's halo stage (its ghost ring, its exchange, the step's exact sums)
// projected onto a network from the cost per block-step measured here.
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>

#include "cdem/core/exact_sum.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/solver/bench.hpp"
#include "cdem/solver/run.hpp"

namespace cdem {
namespace {

// ns per block-step on one core: the 30k box (tied, Mohr-Coulomb, one bar), 100 steps after
// 20 untimed ones, best of 3.
double measure_step_ns() {
  const double h = 0.05;
  const auto cells = bench::tet_cells_for(30000);
  const Vec3 extent{h * cells[0], h * cells[1], h * cells[2]};
  const Case c = bench::box_case(3, extent, h, InterfaceLaw::MohrCoulomb, 1);
  const Mesh mesh = bench::structured_tet_box(cells[0], cells[1], cells[2], h);
  omp_set_num_threads(1);
  PreparedCase pc = prepare_case(c, mesh);
  add_charge_loads(pc);
  for (int s = 0; s < 20; ++s) pc.sim.step();
  double best = 1e300;
  for (int rep = 0; rep < 3; ++rep) {
    const double t0 = omp_get_wtime();
    for (int s = 0; s < 100; ++s) pc.sim.step();
    best = std::min(best, omp_get_wtime() - t0);
  }
  return best / (100.0 * static_cast<double>(pc.sim.model().n_blocks())) * 1e9;
}

// ns to sum one term exactly (core/exact_sum.hpp) on one core: 4 M terms of mixed
// signs and magnitudes into 6 sums, as the step's sums list them; best of 3.
double measure_sum_ns() {
  std::vector<double> x(std::size_t{1} << 22);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::ldexp((i % 7 ? 1.0 : -1.0) * (1.0 + 1e-3 * static_cast<double>(i % 997)), static_cast<int>(i % 41) - 20);
  double best = 1e300, sink = 0;
  for (int rep = 0; rep < 3; ++rep) {
    const double t0 = omp_get_wtime();
    const auto s = sum_exactly(6, [&](auto&& put) {
      for (std::size_t i = 0; i < x.size(); ++i) put(i % 6, x[i]);
    });
    best = std::min(best, omp_get_wtime() - t0);
    sink += s[0];
  }
  if (!(sink == sink)) std::printf("\n");  // (keeps the sums)
  return best / static_cast<double>(x.size()) * 1e9;
}

// The terms of the step's sums (Simulation::step_sums) for the bench box's case, each with a block
// whose part owns it: tied mode, its bottom fixed (a constrained vertex: two reaction terms) and
// its four sides non-reflecting (a node of a block with a face on them: four work terms; all
// counted, as once the waves have reached the sides). (block, terms) per entry; a fixed vertex
// goes with the lowest block that has a base face at it (the run's owner, vertex_owner, takes the
// block of its lowest node among all its blocks: close enough for the busiest part's count).
std::vector<std::pair<std::int32_t, double>> bench_sum_terms(const Mesh& mesh) {
  std::vector<std::int32_t> identity(mesh.num_elements());
  std::iota(identity.begin(), identity.end(), 0);
  std::vector<FaceRec> faces = sorted_faces(mesh, identity);
  std::vector<FaceRec> boundary;  // faces of one element, by key
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (i + 1 < faces.size() && faces[i].key == faces[i + 1].key) {
      ++i;
      continue;
    }
    boundary.push_back(faces[i]);
  }
  std::vector<FaceRec>().swap(faces);
  std::vector<std::uint64_t> nodes;  // (element, vertex)
  std::vector<std::uint64_t> fixed;  // (vertex, an element at it)
  for (const auto& set : mesh.face_sets) {
    const bool bottom = set.name == "bottom";
    for (const auto& f : set.facets) {
      const int nf = f.count();
      FaceRec r{{-1, -1, -1}, 0, 0};
      std::copy(f.v.begin(), f.v.begin() + nf, r.key.begin());
      std::sort(r.key.begin(), r.key.begin() + nf);
      const auto it = std::lower_bound(boundary.begin(), boundary.end(), r,
                                       [](const FaceRec& a, const FaceRec& b) { return a.key < b.key; });
      if (it == boundary.end() || it->key != r.key) continue;
      for (int k = 0; k < nf; ++k) {
        const auto block = static_cast<std::uint32_t>(it->block), vertex = static_cast<std::uint32_t>(f.v[k]);
        if (bottom)
          fixed.push_back((static_cast<std::uint64_t>(vertex) << 32) | block);
        else
          nodes.push_back((static_cast<std::uint64_t>(block) << 32) | vertex);
      }
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::sort(fixed.begin(), fixed.end());
  std::vector<std::pair<std::int32_t, double>> out;
  for (auto e : nodes) out.emplace_back(static_cast<std::int32_t>(e >> 32), 4.0);
  for (std::size_t i = 0; i < fixed.size(); ++i)  // (each vertex once, with its lowest block)
    if (i == 0 || (fixed[i] >> 32) != (fixed[i - 1] >> 32)) out.emplace_back(static_cast<std::int32_t>(fixed[i] & 0xffffffffu), 2.0);
  return out;
}

}  // namespace

int run_partition_projection(const BenchOptions& opt) {
  if (!have_metis()) {
    std::fprintf(stderr, "error: bench --partition: this cdemblast was built without METIS "
                         "(install libmetis-dev and rebuild)\n");
    return 1;
  }
  const double step_ns = opt.step_ns > 0 ? opt.step_ns : measure_step_ns();
  StepSums sums;
  sums.seconds_per_term = measure_sum_ns() * 1e-9;
  const Network net;
  std::vector<std::int64_t> sizes = opt.partition_blocks;
  if (sizes.empty()) sizes.push_back(opt.blocks);
  std::string json = fmt::format("{{\"ns_per_block_step_1_core\": {:.4g}, \"latency_s\": {:.3g}, "
                                 "\"bandwidth_bytes_s\": {:.4g}, \"models\": [",
                                 step_ns, net.latency, net.bandwidth);
  if (!opt.json)
    std::printf("cost per block-step on one core: %.1f ns (%s); network: %.0f Gb/s, %.1f us per "
                "message; no overlap of communication and computation; the step's sums: %.1f ns per "
                "term summed exactly (measured), two collectives (%.0f bytes reduced)\n",
                step_ns, opt.step_ns > 0 ? "given" : "measured on the 30k box, 1 thread",
                net.bandwidth * 8 / 1e9, net.latency * 1e6, sums.seconds_per_term * 1e9, sums.reduce_bytes);
  for (std::size_t si = 0; si < sizes.size(); ++si) {
    const auto cells = bench::tet_cells_for(std::max<std::int64_t>(6, sizes[si]));
    double t0 = omp_get_wtime();
    Mesh mesh = bench::structured_tet_box(cells[0], cells[1], cells[2], 0.05);
    const double mesh_s = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    const BlockGraph g = mesh_block_graph(mesh);
    const double graph_s = omp_get_wtime() - t0;
    const auto sum_terms = bench_sum_terms(mesh);
    sums.terms = 0;
    for (const auto& [b, t] : sum_terms) sums.terms += t;
    Mesh().vertices.swap(mesh.vertices);
    mesh = Mesh();
    double wsum = 0;
    for (auto w : g.vwgt) wsum += w;
    const double s_per_unit = step_ns * 1e-9 * static_cast<double>(g.n()) / wsum;
    if (!opt.json)
      std::printf("\nbench box %d x %d x %d cubes: %zu blocks, %zu interfaces; mesh %.2f s, graph "
                  "%.2f s; the step's sums: %.0f terms\n"
                  "parts  METIS s  blocks/part  imbalance  cut %%  ghosts/part (mean, max)  stepped/model  "
                  "neighbours (mean, max)  kB/step/part (mean, max)  compute us  comm us  sums us  "
                  "compute/comm  efficiency\n",
                  cells[0], cells[1], cells[2], g.n(), g.adjncy.size() / 2, mesh_s, graph_s, sums.terms);
    json += fmt::format("{}{{\"blocks\": {}, \"interfaces\": {}, \"mesh_s\": {:.4g}, \"graph_s\": "
                        "{:.4g}, \"sum_terms\": {}, \"sum_ns_per_term\": {:.4g}, \"partitions\": [",
                        si ? ", " : "", g.n(), g.adjncy.size() / 2, mesh_s, graph_s, sums.terms, sums.seconds_per_term * 1e9);
    for (std::size_t pi = 0; pi < opt.partition_parts.size(); ++pi) {
      const int parts = opt.partition_parts[pi];
      t0 = omp_get_wtime();
      const auto part = partition_kway(g, parts);
      const double metis_s = omp_get_wtime() - t0;
      const auto q = partition_quality(g, part, parts);
      std::vector<double> part_terms(static_cast<std::size_t>(parts), 0.0);
      for (const auto& [b, t] : sum_terms) part_terms[static_cast<std::size_t>(part[static_cast<std::size_t>(b)])] += t;
      sums.terms_max = *std::max_element(part_terms.begin(), part_terms.end());
      const auto pr = project(g, q, s_per_unit, net, sums);
      if (!opt.json)
        std::printf("%5d  %7.1f  %11.0f  %9.3f  %5.2f  %10.0f %9lld  %13.3f  %8.1f %7d  %12.0f %9.0f  "
                    "%10.1f %8.1f %7.1f  %12.1f  %9.3f\n",
                    parts, metis_s, static_cast<double>(g.n()) / parts, q.imbalance,
                    100 * q.edge_cut_share, q.ghosts_mean, static_cast<long long>(q.ghosts_max),
                    q.stepped_share, q.neighbours_mean, q.neighbours_max, q.bytes_mean / 1e3,
                    q.bytes_max / 1e3, pr.compute_s * 1e6, pr.comm_s * 1e6, pr.sums_s * 1e6, pr.ratio,
                    pr.efficiency);
      json += fmt::format(
          "{}{{\"parts\": {}, \"metis_s\": {:.4g}, \"imbalance\": {:.5g}, \"edge_cut\": {}, "
          "\"edge_cut_share\": {:.5g}, \"ghosts_mean\": {:.5g}, \"ghosts_max\": {}, "
          "\"neighbours_mean\": {:.4g}, \"neighbours_max\": {}, \"bytes_mean\": {:.5g}, "
          "\"bytes_max\": {:.5g}, \"stepped_share\": {:.5g}, \"stepped_max\": {:.5g}, \"compute_s\": {:.5g}, "
          "\"comm_s\": {:.5g}, \"sums_s\": {:.5g}, \"sum_terms_max\": {:.5g}, \"ratio\": {:.5g}, \"efficiency\": {:.5g}}}",
          pi ? ", " : "", parts, metis_s, q.imbalance, q.edge_cut, q.edge_cut_share, q.ghosts_mean,
          q.ghosts_max, q.neighbours_mean, q.neighbours_max, q.bytes_mean, q.bytes_max, q.stepped_share,
          q.stepped_max, pr.compute_s, pr.comm_s, pr.sums_s, sums.terms_max, pr.ratio, pr.efficiency);
      std::fflush(stdout);
    }
    json += "]}";
  }
  json += "]}";
  if (opt.json) std::printf("%s\n", json.c_str());
  return 0;
}

}  // namespace cdem
