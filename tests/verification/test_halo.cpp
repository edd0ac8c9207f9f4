// The halo stage's local models in one process (halo_check.hpp): every part stepped beside the
// whole model, its ghosts copied from it before each step, gets the whole model's bits for its
// own blocks. Without ring 2 of the ghost zone (halo.hpp) the unstructured 2D plate in tied mode
// differs at step 23; with both rings, neither model differs in any step.
#include "verification/halo_check.hpp"

namespace cdem {
namespace {

using namespace halo_check;

void check_all_parts(const HaloCase& hc, int nparts, std::int64_t steps) {
  const auto part = parts_of(hc.model, nparts);
  std::vector<int> all(static_cast<std::size_t>(nparts));
  for (int p = 0; p < nparts; ++p) all[static_cast<std::size_t>(p)] = p;
  EXPECT_GT(step_parts(hc, part, nparts, all, steps, copy_ghosts), 0) << hc.what;
}

TEST(Halo, TetBoxPartsGetTheWholeModelsBits) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_all_parts(spall_box(mode), 3, 60);
}

TEST(Halo, Plate2DPartsGetTheWholeModelsBits) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_all_parts(plate_2d(mode), 4, 120);
}

// Every block is owned by one part, and a part's ghosts are the ring of halo.hpp: every block
// sharing a vertex with an own block, and no other.
TEST(Halo, OwnershipAndRings) {
  const HaloCase hc = plate_2d(InterfaceMode::Tied);
  const Model& m = hc.model;
  const auto part = parts_of(m, 4);
  std::vector<int> owners(m.n_blocks(), 0);
  for (int p = 0; p < 4; ++p) {
    const PartModel pm = cut_part(m, part, p);
    std::vector<std::uint8_t> local(m.n_blocks(), 0), own_vertex(m.vertex_X.size(), 0);
    for (std::size_t k = 0; k < pm.block.size(); ++k) {
      const auto b = static_cast<std::size_t>(pm.block[k]);
      local[b] = 1;
      owners[b] += pm.own[k];
      EXPECT_EQ(pm.own[k] != 0, part[b] == p);
      if (pm.own[k])
        for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) own_vertex[static_cast<std::size_t>(m.node_vertex[n])] = 1;
    }
    // the ring: a block is local exactly when it has a vertex of an own block
    for (std::size_t b = 0; b < m.n_blocks(); ++b) {
      bool touches = false;
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) touches = touches || own_vertex[static_cast<std::size_t>(m.node_vertex[n])];
      EXPECT_EQ(local[b] != 0, touches) << "block " << b << ", part " << p;
    }
    // the local model: its interfaces are those between two local blocks, in the global order
    EXPECT_TRUE(std::is_sorted(pm.iface.begin(), pm.iface.end()));
    std::size_t both = 0;
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) both += local[static_cast<std::size_t>(m.iface_block_a[i])] && local[static_cast<std::size_t>(m.iface_block_b[i])];
    EXPECT_EQ(both, pm.iface.size());
    EXPECT_EQ(pm.model.n_nodes(), pm.node.size());
  }
  for (std::size_t b = 0; b < m.n_blocks(); ++b) EXPECT_EQ(owners[b], 1) << "block " << b;
}

}  // namespace
}  // namespace cdem
