// Domain decomposition of the block graph (issue 17, first part): METIS k-way partitions of the
// blocks, and what a distributed run would exchange with them (docs/parallel.md).
//
// The graph: a vertex per block, an edge per interface (two blocks sharing a face). Vertex
// weights are the blocks' step cost (block_weight), edge weights the interface's spring points
// (the data an owner sends across per step); blocks that one charge binds get a heavy edge
// between them, so that a cut through a charge is avoided where the balance allows it.
//
// The exchange model (partition_quality) is the halo stage's (parallel/halo.hpp), as built: each
// part steps its own blocks and a ghost zone (every block sharing a mesh vertex with an own
// block). Per step a part receives its ghost
// blocks' node positions and velocities (6 doubles per node) from their owners and sends as much
// for its own blocks that are ghosts elsewhere: one message each way per neighbouring part. Every
// rank also joins two collectives per step (the step's exact sums, one MPI_Allreduce of their
// bins, and the stop signal).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "cdem/mesh/mesh.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

// CSR graph in METIS's layout (xadj has n + 1 entries).
struct BlockGraph {
  std::vector<std::int32_t> xadj, adjncy, vwgt, adjwgt;
  // each block's mesh vertices (CSR; a CDEM block has a node per vertex): the halo's vertex ring
  std::vector<std::int32_t> bv_offset;
  std::vector<std::int32_t> bv;
  int points_per_iface = 3;  // spring points per interface: 2 in 2D, 3 in 3D
  std::size_t n() const { return xadj.empty() ? 0 : xadj.size() - 1; }
};

// Mesh vertex -> the blocks holding it, ascending, as CSR (`start`: a vertex count + 1 entries),
// from block -> its vertices (`offset`: a block count + 1 entries; a model's block_first_node and
// node_vertex, or a graph's bv_offset and bv).
void vertex_blocks(const std::vector<std::int32_t>& offset, const std::vector<std::int32_t>& vertices,
                   std::vector<std::int32_t>& start, std::vector<std::int32_t>& list);

// Step cost of a block in weight units, from the kernel split of `cdemblast bench` (tied mode,
// 1 thread, docs/performance.md): the block kernel ~10 units per tetrahedron (quad 8, triangle
// 4, all at ~5 ns per unit), plus 1 per interface (the tie check, and the spring update once the
// interface opens, shared by its two blocks).
std::int32_t block_weight(ElemType type, int interfaces);

// The graph of a model (its interfaces). `together`: per block a group id (>= 0) for blocks
// that must stay in one part where possible (bound to one charge), -1 otherwise; may be empty.
BlockGraph block_graph(const Model& m, const std::vector<std::int32_t>& together = {});
// The same graph from a mesh (elements sharing a face), without building the model: for
// partitioning models too large to set up on this machine (the scale projection).
BlockGraph mesh_block_graph(const Mesh& mesh);

// Per block the charge that binds it (bar b: b; solid charge c: number of bars + c), -1 for the
// others: the `together` groups of block_graph.
struct BarCharges;
struct SolidCharges;
std::vector<std::int32_t> charge_groups(std::size_t n_blocks, const BarCharges& bars,
                                        const SolidCharges& solids);

// Contiguous ranges of the block order, of nearly equal weight (g.vwgt): part r holds blocks
// [first[r], first[r + 1]) (parts + 1 entries, first[0] = 0, first[parts] = n). The block order
// is a Hilbert curve through the model (mesh_order.hpp), so a range is a compact piece of it
// (the space-filling-curve partition of Zoltan's HSFC). The distributed run's ownership in its
// replicated stage (ranks.hpp); each cut is placed at the block boundary nearest to its share
// of the total weight.
std::vector<std::int64_t> block_ranges(const BlockGraph& g, int parts);
// The same as a part per block (the layout of partition_kway and partition_quality).
std::vector<std::int32_t> ranges_to_parts(const std::vector<std::int64_t>& first);

// True when the program was built with METIS.
bool have_metis();

// METIS_PartGraphKway into `parts` parts (edge-cut objective, load imbalance tolerance
// `ufactor`, e.g. 1.03), fixed seed: the same partition on every run. parts == 1 gives all
// zeros. Throws std::runtime_error without METIS or when METIS fails.
std::vector<std::int32_t> partition_kway(const BlockGraph& g, int parts, double ufactor = 1.03);

struct PartitionQuality {
  int parts = 0;
  std::int64_t edge_cut = 0;        // interfaces whose two blocks are in different parts
  double edge_cut_share = 0;        // of all interfaces
  double imbalance = 0;             // max part weight / mean part weight
  std::int64_t blocks_min = 0, blocks_max = 0;
  // The halo stage's ghost zone (halo.hpp) and exchange, per part: its ghost blocks,
  // the weight it steps (own + ghosts), its neighbours, the bytes it receives + sends per step.
  std::int64_t ghosts_max = 0;      // ghost blocks of the part with the most
  double ghosts_mean = 0;
  double stepped_max = 0;           // weight stepped (own + ghost blocks) by the busiest part
  double stepped_share = 0;         // sum over the parts of the weight stepped / the model's
  int neighbours_max = 0;           // parts a part exchanges with
  double neighbours_mean = 0;
  double bytes_max = 0, bytes_mean = 0;  // bytes received + sent per part per step
  double messages_max = 0;               // point-to-point messages per part per step (both ways)
  std::int64_t together_split = 0;  // groups of `together` blocks spread over more than 1 part
};
// Needs g.bv (the vertex ring) when parts > 1; throws std::invalid_argument without it.
PartitionQuality partition_quality(const BlockGraph& g, const std::vector<std::int32_t>& part, int parts,
                                   const std::vector<std::int32_t>& together = {});

// A network for the projection: latency (s) per message and bandwidth (bytes/s).
struct Network {
  double latency = 2e-6;
  double bandwidth = 100e9 / 8;  // 100 Gb/s
};
// Per step of the busiest part (parallel/halo.hpp, as built; docs/parallel.md):
//   compute = its stepped weight (own + ghost blocks) x (seconds per weight unit)
//             + its own terms of the step's sums x seconds per term (exact sums:
//             Simulation::step_sums);
//   comm    = its messages x latency + its bytes / bandwidth
//             + ceil(log2 parts) x (2 latencies + the sums' bytes / bandwidth) (two collectives,
//               recursive doubling: the sums' bins, and the stop signal);
// efficiency without overlap = compute(1 process) / parts / (compute + comm), where one process
// steps the model's weight and sums all the terms.
struct StepSums {
  double terms = 0;                // terms per step over the whole model
  double terms_max = 0;            // the busiest part's own terms (for the partition projected)
  double seconds_per_term = 3e-9;  // to sum one of them exactly (measured: bench --partition)
  // the bytes reduced: Simulation::step_sums's 12 sums, each 193 int64 (ExactSums::result)
  double reduce_bytes = 8.0 * 193 * 12;
};
struct Projection {
  double compute_s = 0, comm_s = 0, ratio = 0, efficiency = 0;
  double sums_s = 0;  // of compute_s + comm_s: the step's sums (the busiest part's terms, the collectives)
};
Projection project(const BlockGraph& g, const PartitionQuality& q, double seconds_per_unit,
                   const Network& net, const StepSums& sums = {});

}  // namespace cdem
