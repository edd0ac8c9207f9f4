// The processes of a distributed run: MPI ranks (docs/parallel.md).
//
// `mpirun -np N cdemblast run CASE` starts N processes of the same program on the same case.
// Each holds the whole model and steps it; the block kernel is divided among them by
// contiguous ranges of the blocks' Hilbert order (block_ranges, partition.hpp) and the spring
// kernel by equal shares of the list it steps, and each step the ranks share what their shares
// computed (share_slices) before anything reads it. Every value is computed by exactly one rank, with
// the same arithmetic as on one rank, and every sum runs over the whole model in its fixed
// order on every rank: so N ranks give the results of one bit for bit, and every rank holds
// the same state. Rank 0 writes the output.
//
// This is the first stage of issue 17: the state is replicated (a rank's memory is the whole
// model's), and only the block and spring kernels are divided. docs/parallel.md says what the halo stage
// will change.
//
// Without MPI at build time, or when the program was not started by an MPI launcher (no
// OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK in the environment), there is one rank and every
// function here is a no-op.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "cdem/core/exact_sum.hpp"

namespace cdem {

struct RankInfo {
  int rank = 0;
  int size = 1;
  int local_size = 1;  // ranks on this machine (they share its cores)
  bool root() const { return rank == 0; }
};

// This process's rank and the number of ranks (0 of 1 before RankSession or without MPI).
const RankInfo& ranks();
// True when the program was built with MPI.
bool have_mpi();

// MPI's lifetime: MPI_Init_thread (funneled: OpenMP threads never call MPI) when launched by an
// MPI launcher, MPI_Finalize at the end (finish).
class RankSession {
 public:
  RankSession(int* argc, char*** argv);
  ~RankSession();
  RankSession(const RankSession&) = delete;
  RankSession& operator=(const RankSession&) = delete;
  // The program's exit code. Under N ranks an exit code of 1 or 2 (an error: it may have hit
  // one rank only, the others then wait in an exchange) ends every rank with MPI_Abort; any
  // other code (a finished, unstable or interrupted run: every rank ends it at the same step)
  // finalizes normally.
  int finish(int rc);
};

// In place, every rank's slice of `data` to every rank: rank r computed the elements
// [first[r], first[r + 1]) (first has size() + 1 entries), each `stride` doubles.
void share_slices(double* data, const std::vector<std::int64_t>& first, int stride);
// Every rank's `send[q]` to rank q, received as `recv[q]` from q (sizes: one list per rank;
// recv is resized). Set-up only (MPI_Alltoall of the counts, MPI_Alltoallv).
void all_to_all(const std::vector<std::vector<std::int32_t>>& send, std::vector<std::vector<std::int32_t>>& recv);
// One exchange with the ranks `peers`: send[k] to peers[k] and recv[k] from it (recv[k] sized
// by the caller to what peers[k] sends), all at once (MPI_Irecv, MPI_Isend, MPI_Waitall).
void exchange_with(const std::vector<int>& peers, const std::vector<std::vector<double>>& send,
                   std::vector<std::vector<double>>& recv);
// Every rank's `mine`, concatenated in rank order, to every rank; `first` gets each rank's
// offset in the result (size() + 1 entries). MPI_Allgather of the counts, MPI_Allgatherv.
void gather_all(const std::vector<double>& mine, std::vector<double>& all, std::vector<std::int64_t>& first);
// The same to rank 0 only (MPI_Gather of the counts, MPI_Gatherv); on the other ranks `all` is
// empty and `first` all zeros.
void gather_to_root(const std::vector<double>& mine, std::vector<double>& all, std::vector<std::int64_t>& first);
// The largest of `v` over the ranks.
std::int64_t max_over_ranks(std::int64_t v);
// The collective of exact_sum.hpp's sums over the ranks (MPI_Allreduce, MPI_SUM of int64); null
// with one rank.
const SumReducer* rank_reducer();
// True when `h` is the same on every rank (a check that the ranks' states agree).
bool same_over_ranks(std::uint64_t h);

}  // namespace cdem
