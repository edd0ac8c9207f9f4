// The halo stage over MPI (halo_check.hpp): one part per rank, its ghosts' positions and
// velocities received from their owners each step (HaloExchange, parallel/halo.hpp), gets the
// whole model's bits for its own blocks, step after step. Each rank also steps the whole model
// (the reference). Run by ctest with mpirun on 2, 3 and 4 ranks (CMakeLists.txt).
#include <gtest/gtest.h>

#include <cstdio>

#include "cdem/parallel/ranks.hpp"
#include "verification/halo_check.hpp"

namespace cdem {
namespace {

using namespace halo_check;

void check_my_part(const HaloCase& hc, std::int64_t steps) {
  const int n = ranks().size, r = ranks().rank;
  ASSERT_GT(n, 1) << "run under mpirun with 2 ranks or more";
  const auto part = parts_of(hc.model, n);
  std::unique_ptr<HaloExchange> halo;
  const Refresh refresh = [&](int, const PartModel& pm, Simulation& sim, const Simulation&) {
    if (!halo) halo = std::make_unique<HaloExchange>(pm, part);
    halo->exchange(sim.model());
  };
  const std::int64_t cut = step_parts(hc, part, n, {r}, steps, refresh);
  ASSERT_TRUE(halo);
  EXPECT_FALSE(halo->peers().empty());
  EXPECT_GT(halo->nodes_received(), 0u);
  // the same whole model on every rank: the cracks between parts are counted alike
  EXPECT_GT(cut, 0) << hc.what;
  EXPECT_EQ(max_over_ranks(cut), cut);
}

TEST(HaloMpi, TetBox) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_my_part(spall_box(mode), 60);
}

TEST(HaloMpi, Plate2D) {
  for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) check_my_part(plate_2d(mode), 120);
}

}  // namespace
}  // namespace cdem

namespace {
cdem::RankSession* g_session = nullptr;
// A failure on one rank ends every rank (MPI_Abort): the others would wait for its messages.
class AbortOnFailure : public ::testing::EmptyTestEventListener {
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (!r.failed()) return;
    std::fprintf(stderr, "rank %d: %s:%d: %s\n", cdem::ranks().rank, r.file_name() ? r.file_name() : "?",
                 r.line_number(), r.summary());
    std::fflush(stderr);
    g_session->finish(1);
  }
};
}  // namespace

int main(int argc, char** argv) {
  cdem::RankSession session(&argc, &argv);
  g_session = &session;
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::UnitTest::GetInstance()->listeners().Append(new AbortOnFailure);
  // (only rank 0 prints gtest's report; every rank's failures set its exit code, which mpirun returns)
  if (!cdem::ranks().root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int rc = RUN_ALL_TESTS();
  return session.finish(rc == 0 ? 0 : 3);
}
