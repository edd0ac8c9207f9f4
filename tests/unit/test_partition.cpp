// Domain decomposition (src/cdem/parallel/partition.*, issue 17, docs/parallel.md): the METIS
// k-way partition of the block graph and its quality on the bench model.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "cdem/parallel/halo.hpp"
#include "cdem/parallel/partition.hpp"
#include "cdem/solver/bench.hpp"
#include "cdem/solver/run.hpp"

namespace cdem {
namespace {

PreparedCase bench_box(std::int64_t blocks, int bars) {
  const double h = 0.05;
  const auto cells = bench::tet_cells_for(blocks);
  const Vec3 extent{h * cells[0], h * cells[1], h * cells[2]};
  const Case c = bench::box_case(3, extent, h, InterfaceLaw::MohrCoulomb, bars);
  return prepare_case(c, bench::structured_tet_box(cells[0], cells[1], cells[2], h));
}

// The graph from the mesh (shared faces) is the model's graph (its interfaces): same edges.
TEST(Partition, MeshGraphIsTheModelGraph) {
  const auto cells = bench::tet_cells_for(3000);
  const Mesh mesh = bench::structured_tet_box(cells[0], cells[1], cells[2], 0.05);
  const Model m = build_case_model(bench::box_case(3, {1, 1, 1}, 0.05, InterfaceLaw::MohrCoulomb, 0), mesh);
  const BlockGraph a = mesh_block_graph(mesh), b = block_graph(m);
  ASSERT_EQ(a.n(), b.n());
  ASSERT_EQ(a.adjncy.size(), b.adjncy.size());
  EXPECT_EQ(a.vwgt, b.vwgt);
  for (std::size_t v = 0; v < a.n(); ++v) {
    std::set<int> na(a.adjncy.begin() + a.xadj[v], a.adjncy.begin() + a.xadj[v + 1]);
    std::set<int> nb(b.adjncy.begin() + b.xadj[v], b.adjncy.begin() + b.xadj[v + 1]);
    ASSERT_EQ(na, nb) << "block " << v;
  }
}

// Issue 17: the imbalance on the bench model at or below 5 %; every part non-empty; the same
// partition on every call (fixed seed); a cut that is a small share of the interfaces (a
// surface-to-volume ratio: at 16 parts of ~1 800 tets, a few %).
TEST(Partition, BenchModelBalanced) {
  if (!have_metis()) GTEST_SKIP() << "built without METIS";
  const PreparedCase pc = bench_box(30000, 1);
  const Model& m = pc.sim.model();
  const auto groups = charge_groups(m.n_blocks(), pc.bars, pc.solids);
  const BlockGraph g = block_graph(m, groups);
  for (int parts : {2, 3, 4, 16}) {
    const auto part = partition_kway(g, parts);
    ASSERT_EQ(part.size(), m.n_blocks());
    EXPECT_EQ(part, partition_kway(g, parts)) << parts << " parts: not reproducible";
    std::vector<int> count(parts, 0);
    for (auto p : part) {
      ASSERT_GE(p, 0);
      ASSERT_LT(p, parts);
      ++count[p];
    }
    EXPECT_GT(*std::min_element(count.begin(), count.end()), 0);
    const auto q = partition_quality(g, part, parts, groups);
    std::printf("[partition] %d parts: imbalance %.4f, cut %.2f %%, ghosts %.0f / %lld, charges split %lld\n",
                parts, q.imbalance, 100 * q.edge_cut_share, q.ghosts_mean,
                static_cast<long long>(q.ghosts_max), static_cast<long long>(q.together_split));
    EXPECT_LE(q.imbalance, 1.05) << parts << " parts";
    EXPECT_LT(q.edge_cut_share, 0.08) << parts << " parts";
    EXPECT_EQ(q.together_split, 0) << parts << " parts: a bar's blocks were split";
  }
}

// The exchange model counts what it says. A 2 x 1 x 1 box of two cubes (6 tets each), one cube
// per part: the square between the cubes is split into 2 triangles, so 2 interfaces are cut. Each
// cube's 6 tets share its main diagonal, whose one end is on the square: every tet of one cube
// shares a vertex with the other cube, so each part's ghost zone (ring 1) is the other cube's 6
// tets, and each part has 1 neighbour.
TEST(Partition, QualityCountsTheCut) {
  const Mesh mesh = bench::structured_tet_box(2, 1, 1, 1.0);
  const BlockGraph g = mesh_block_graph(mesh);
  ASSERT_EQ(g.n(), 12u);
  std::vector<std::int32_t> part(12);
  for (int e = 0; e < 12; ++e) part[e] = e < 6 ? 0 : 1;  // first cube, second cube
  const auto q = partition_quality(g, part, 2);
  EXPECT_EQ(q.edge_cut, 2);
  EXPECT_EQ(q.ghosts_max, 6);
  EXPECT_EQ(q.neighbours_max, 1);
  EXPECT_DOUBLE_EQ(q.messages_max, 2.0);
  // 6 ghosts x 4 nodes x 6 doubles x 8 bytes, received and sent
  EXPECT_DOUBLE_EQ(q.bytes_max, 2 * (6 * 4 * 6 * 8));
  EXPECT_DOUBLE_EQ(q.stepped_share, 2.0);  // each part steps the whole box
  EXPECT_DOUBLE_EQ(q.imbalance, 1.0);
}

// The exchange model's ghost zones are the halo stage's (halo.cpp, part_blocks, which the
// distributed runs step): on the bench box in 2, 3 and 7 METIS parts, each part's ghost blocks,
// the weight it steps, the bytes it receives and its neighbours, counted here from part_blocks's
// zones, give the same maxima and means as partition_quality (which forms every zone at once
// from the vertex and face lists).
TEST(Partition, QualityCountsTheHaloZone) {
  if (!have_metis()) GTEST_SKIP() << "built without METIS";
  const auto cells = bench::tet_cells_for(3000);
  const Mesh mesh = bench::structured_tet_box(cells[0], cells[1], cells[2], 0.05);
  const Model m = build_case_model(bench::box_case(3, {1, 1, 1}, 0.05, InterfaceLaw::MohrCoulomb, 0), mesh);
  const BlockGraph g = block_graph(m);
  for (int parts : {2, 3, 7}) {
    const auto part = partition_kway(g, parts);
    const auto q = partition_quality(g, part, parts);
    std::int64_t ghosts_max = 0;
    double ghosts_sum = 0, stepped_max = 0, recv_sum = 0;
    std::vector<double> bytes(parts, 0.0);
    std::vector<std::set<int>> peers(parts);
    for (int p = 0; p < parts; ++p) {
      std::vector<std::int32_t> blocks;
      std::vector<std::uint8_t> own;
      part_blocks(m, part, p, blocks, own);
      std::int64_t ghosts = 0;
      double stepped = 0;
      for (std::size_t k = 0; k < blocks.size(); ++k) {
        const auto b = static_cast<std::size_t>(blocks[k]);
        stepped += g.vwgt[b];
        if (own[k]) continue;
        ++ghosts;
        const double state = 48.0 * (m.block_first_node[b + 1] - m.block_first_node[b]);
        bytes[p] += state;
        bytes[part[b]] += state;
        recv_sum += state;
        peers[p].insert(part[b]);
        peers[part[b]].insert(p);
      }
      ghosts_max = std::max(ghosts_max, ghosts);
      ghosts_sum += static_cast<double>(ghosts);
      stepped_max = std::max(stepped_max, stepped);
    }
    std::size_t nmax = 0;
    for (const auto& s : peers) nmax = std::max(nmax, s.size());
    EXPECT_EQ(q.ghosts_max, ghosts_max) << parts << " parts";
    EXPECT_DOUBLE_EQ(q.ghosts_mean, ghosts_sum / parts) << parts << " parts";
    EXPECT_DOUBLE_EQ(q.stepped_max, stepped_max) << parts << " parts";
    EXPECT_DOUBLE_EQ(q.bytes_max, *std::max_element(bytes.begin(), bytes.end())) << parts << " parts";
    EXPECT_NEAR(q.bytes_mean, 2 * recv_sum / parts, 1e-9 * recv_sum) << parts << " parts";
    EXPECT_EQ(q.neighbours_max, static_cast<int>(nmax)) << parts << " parts";
    EXPECT_GT(q.ghosts_max, 0);
  }
}

// The ranks' division of a distributed run (block_ranges): contiguous ranges that cover every
// block once, in order, with the weights balanced to one block's weight (the cut is at the
// block boundary nearest each share: the largest part exceeds the mean by at most one block's
// weight, ~15 units against ~15 000 per part at 30k blocks and 16 parts, so 1 % is generous
// and 5 % is the bound); every part non-empty; compact parts: a scattered division
// cuts 1 - 1/parts of the interfaces (94 % at 16 parts), the Hilbert ranges 16 % at 16 parts
// (METIS 5 %: docs/parallel.md), so the bound is 25 %.
TEST(Partition, RankRangesBalanced) {
  const PreparedCase pc = bench_box(30000, 1);
  const BlockGraph g = block_graph(pc.sim.model());
  const auto n = static_cast<std::int64_t>(g.n());
  std::int32_t wmax = *std::max_element(g.vwgt.begin(), g.vwgt.end());
  for (int parts : {1, 2, 3, 4, 16}) {
    const auto first = block_ranges(g, parts);
    ASSERT_EQ(first.size(), static_cast<std::size_t>(parts + 1));
    EXPECT_EQ(first.front(), 0);
    EXPECT_EQ(first.back(), n);
    std::int64_t total = 0, wmax_part = 0;
    for (int r = 0; r < parts; ++r) {
      ASSERT_LT(first[r], first[r + 1]) << parts << " parts: part " << r << " empty";
      std::int64_t w = 0;
      for (auto b = first[r]; b < first[r + 1]; ++b) w += g.vwgt[b];
      total += w;
      wmax_part = std::max(wmax_part, w);
    }
    const double mean = static_cast<double>(total) / parts;
    EXPECT_LE(wmax_part, mean + wmax) << parts << " parts";
    const auto q = partition_quality(g, ranges_to_parts(first), parts);
    EXPECT_LE(q.imbalance, 1.01) << parts << " parts";
    if (parts > 1) {
      EXPECT_LT(q.edge_cut_share, 0.25) << parts << " parts";
    }
  }
}

}  // namespace
}  // namespace cdem
