#include "cdem/parallel/ranks.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include <fmt/core.h>

#ifdef CDEM_HAVE_MPI
#include <mpi.h>
#endif

namespace cdem {

namespace {
RankInfo g_ranks;
#ifdef CDEM_HAVE_MPI
bool g_mpi = false;  // MPI_Init_thread was called
// Started by an MPI launcher (Open MPI's mpirun, or a PMI/PMIx launcher such as srun): outside
// one, MPI_Init would start a singleton and its runtime for nothing.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}
#endif
}  // namespace

const RankInfo& ranks() { return g_ranks; }

bool have_mpi() {
#ifdef CDEM_HAVE_MPI
  return true;
#else
  return false;
#endif
}

RankSession::RankSession(int* argc, char*** argv) {
#ifdef CDEM_HAVE_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    fmt::print(stderr, "error: MPI_Init_thread failed\n");
    std::exit(1);
  }
  g_mpi = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_ranks.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_ranks.size);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  MPI_Comm_size(local, &g_ranks.local_size);
  MPI_Comm_free(&local);
#else
  (void)argc;
  (void)argv;
  // Started as one of several processes by an MPI launcher, without MPI to talk to the others:
  // each would run the whole case into the same directory.
  const char* n = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!n) n = std::getenv("PMI_SIZE");
  if (n && std::atoi(n) > 1) {
    fmt::print(stderr, "error: this cdemblast was built without MPI (install libopenmpi-dev and "
                       "rebuild): it cannot run as one of {} ranks\n", n);
    std::exit(2);
  }
#endif
}

RankSession::~RankSession() {
#ifdef CDEM_HAVE_MPI
  if (g_mpi) MPI_Finalize();
  g_mpi = false;
#endif
}

int RankSession::finish(int rc) {
#ifdef CDEM_HAVE_MPI
  if (g_mpi && g_ranks.size > 1 && (rc == 1 || rc == 2)) MPI_Abort(MPI_COMM_WORLD, rc);
#endif
  return rc;
}

void share_slices(double* data, const std::vector<std::int64_t>& first, int stride) {
#ifdef CDEM_HAVE_MPI
  if (g_ranks.size == 1) return;
  const int n = g_ranks.size;
  if (static_cast<int>(first.size()) != n + 1)
    throw std::logic_error("share_slices: the slices are not one per rank");
  // Counts in doubles: MPI's counts are int. A model whose one array exceeds 2^31 doubles
  // (700 M nodes' forces) is far beyond what replicated state can hold anyway.
  // (the counts' buffers are grown once: nothing is allocated in a step after the first)
  static std::vector<int> count, displ;
  count.resize(n);
  displ.resize(n);
  for (int r = 0; r < n; ++r) {
    const std::int64_t c = (first[r + 1] - first[r]) * stride, d = first[r] * stride;
    if (c > std::numeric_limits<int>::max() || d > std::numeric_limits<int>::max())
      throw std::runtime_error("share_slices: a slice beyond 2^31 doubles");
    count[r] = static_cast<int>(c);
    displ[r] = static_cast<int>(d);
  }
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, data, count.data(), displ.data(), MPI_DOUBLE,
                 MPI_COMM_WORLD);
#else
  (void)data;
  (void)first;
  (void)stride;
#endif
}

void all_to_all(const std::vector<std::vector<std::int32_t>>& send, std::vector<std::vector<std::int32_t>>& recv) {
  const int n = g_ranks.size;
  if (static_cast<int>(send.size()) != n) throw std::logic_error("all_to_all: not a list per rank");
  recv.assign(static_cast<std::size_t>(n), {});
#ifdef CDEM_HAVE_MPI
  if (n > 1) {
    std::vector<int> sc(n), rc(n), sd(n + 1, 0), rd(n + 1, 0);
    for (int q = 0; q < n; ++q) {
      if (send[q].size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / n))
        throw std::runtime_error("all_to_all: a list beyond MPI's counts");
      sc[q] = static_cast<int>(send[q].size());
    }
    MPI_Alltoall(sc.data(), 1, MPI_INT, rc.data(), 1, MPI_INT, MPI_COMM_WORLD);
    for (int q = 0; q < n; ++q) sd[q + 1] = sd[q] + sc[q], rd[q + 1] = rd[q] + rc[q];
    std::vector<std::int32_t> sbuf(static_cast<std::size_t>(sd[n])), rbuf(static_cast<std::size_t>(rd[n]));
    for (int q = 0; q < n; ++q) std::copy(send[q].begin(), send[q].end(), sbuf.begin() + sd[q]);
    MPI_Alltoallv(sbuf.data(), sc.data(), sd.data(), MPI_INT32_T, rbuf.data(), rc.data(), rd.data(),
                  MPI_INT32_T, MPI_COMM_WORLD);
    for (int q = 0; q < n; ++q) recv[q].assign(rbuf.begin() + rd[q], rbuf.begin() + rd[q + 1]);
    return;
  }
#endif
  recv[0] = send[0];
}

void exchange_with(const std::vector<int>& peers, const std::vector<std::vector<double>>& send,
                   std::vector<std::vector<double>>& recv) {
  if (peers.empty()) return;
#ifdef CDEM_HAVE_MPI
  const std::size_t np = peers.size();
  static std::vector<MPI_Request> req;
  req.assign(2 * np, MPI_REQUEST_NULL);
  constexpr int kTag = 17;
  for (std::size_t k = 0; k < np; ++k)
    MPI_Irecv(recv[k].data(), static_cast<int>(recv[k].size()), MPI_DOUBLE, peers[k], kTag, MPI_COMM_WORLD, &req[k]);
  for (std::size_t k = 0; k < np; ++k)
    MPI_Isend(send[k].data(), static_cast<int>(send[k].size()), MPI_DOUBLE, peers[k], kTag, MPI_COMM_WORLD,
              &req[np + k]);
  MPI_Waitall(static_cast<int>(2 * np), req.data(), MPI_STATUSES_IGNORE);
#else
  (void)send;
  (void)recv;
  throw std::logic_error("exchange_with: peers without MPI");
#endif
}

namespace {
// gather_all (to_root false) and gather_to_root (true)
void gather_doubles(const std::vector<double>& mine, std::vector<double>& all, std::vector<std::int64_t>& first,
                    bool to_root) {
  const int n = g_ranks.size;
  first.assign(static_cast<std::size_t>(n) + 1, 0);
#ifdef CDEM_HAVE_MPI
  if (n > 1) {
    if (mine.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
      throw std::runtime_error("gather_all: a share beyond 2^31 doubles");
    static std::vector<int> count, displ;
    count.assign(static_cast<std::size_t>(n), 0);
    displ.assign(static_cast<std::size_t>(n), 0);
    const int c = static_cast<int>(mine.size());
    if (to_root)
      MPI_Gather(&c, 1, MPI_INT, count.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    else
      MPI_Allgather(&c, 1, MPI_INT, count.data(), 1, MPI_INT, MPI_COMM_WORLD);
    const bool receives = !to_root || g_ranks.rank == 0;
    if (receives) {
      for (int r = 0; r < n; ++r) first[r + 1] = first[r] + count[r];
      if (first[n] > std::numeric_limits<int>::max()) throw std::runtime_error("gather_all: beyond 2^31 doubles in all");
      for (int r = 0; r < n; ++r) displ[r] = static_cast<int>(first[r]);
      all.resize(static_cast<std::size_t>(first[n]));
    } else {
      all.clear();
    }
    if (to_root)
      MPI_Gatherv(mine.data(), c, MPI_DOUBLE, all.data(), count.data(), displ.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD);
    else
      MPI_Allgatherv(mine.data(), c, MPI_DOUBLE, all.data(), count.data(), displ.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    return;
  }
#endif
  (void)to_root;
  all = mine;
  first[1] = static_cast<std::int64_t>(mine.size());
}
}  // namespace

void gather_all(const std::vector<double>& mine, std::vector<double>& all, std::vector<std::int64_t>& first) {
  gather_doubles(mine, all, first, false);
}

void gather_to_root(const std::vector<double>& mine, std::vector<double>& all, std::vector<std::int64_t>& first) {
  gather_doubles(mine, all, first, true);
}

std::int64_t max_over_ranks(std::int64_t v) {
#ifdef CDEM_HAVE_MPI
  if (g_ranks.size == 1) return v;
  std::int64_t out = v;
  MPI_Allreduce(&v, &out, 1, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD);
  return out;
#else
  return v;
#endif
}

const SumReducer* rank_reducer() {
#ifdef CDEM_HAVE_MPI
  if (g_ranks.size == 1) return nullptr;
  static SumReducer r;
  r.ranks = g_ranks.size;
  r.sum = [](std::int64_t* v, std::size_t n) {
    MPI_Allreduce(MPI_IN_PLACE, v, static_cast<int>(n), MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  };
  return &r;
#else
  return nullptr;
#endif
}

bool same_over_ranks(std::uint64_t h) {
#ifdef CDEM_HAVE_MPI
  if (g_ranks.size == 1) return true;
  std::uint64_t in[2] = {h, ~h}, out[2] = {0, 0};
  MPI_Allreduce(in, out, 2, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  return out[0] == h && out[1] == ~h;  // max of h and max of ~h (the min of h) both h
#else
  (void)h;
  return true;
#endif
}

}  // namespace cdem
