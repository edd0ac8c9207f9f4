// Sums whose bits depend neither on the order of their terms nor on how the terms are split
// among ranks (docs/parallel.md "Exact sums"): the step's works, and a history sample's energy
// balance and fracture degree, formed by each rank over what it owns and reduced by one
// collective, with the bits one process gets.
//
// Each sum is held exactly, as a long fixed-point number (Kulisch's long accumulator, cut into
// bins): a double x is m 2^(E - 1075) with m its 53-bit integer significand and E its biased
// exponent (1 for subnormals). It is added, as the 128-bit integer +-m 2^(E mod 32), to bin
// E / 32 of 64, whose weight is 2^(32 (E / 32) - 1075). A bin takes 2^42 terms before it could
// overflow (each is below 2^84 and the bin holds up to 2^126); integers add exactly in any order.
// One pass over the terms; over the ranks, the bins are summed by one MPI_SUM (each bin as three
// 42-bit limbs in int64, so that up to 2^21 ranks cannot overflow a limb). The bins, carried
// into 32-bit digits, are the exact sum, rounded once to the nearest double (ties to even; a
// subnormal result is exact: every sum of doubles is a multiple of 2^-1074).
//
// A sum with a NaN or infinite term is NaN. A zero term adds nothing (-0 too: an empty sum, or one
// of zeros, is +0).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace cdem {

// A 128-bit integer (GCC and Clang; __extension__: not ISO C++).
__extension__ typedef __int128 ExactInt;

// The collective of a distributed sum: in place over n int64 values, every rank's total
// (MPI_Allreduce, MPI_SUM); ranks: how many. null (or one rank): a sum of one process.
struct SumReducer {
  void (*sum)(std::int64_t* v, std::size_t n) = nullptr;
  int ranks = 1;
};

class ExactSums {
 public:
  static constexpr int kBins = 64;
  explicit ExactSums(std::size_t sums = 0) { reset(sums); }
  void reset(std::size_t sums) {
    bins_.assign(sums * kBins, 0);
    bad_.assign(sums, 0);
  }
  std::size_t size() const { return bad_.size(); }

  // Adds x to sum i, exactly.
  void add(std::size_t i, double x) {
    std::uint64_t u;
    std::memcpy(&u, &x, sizeof u);
    if ((u << 1) == 0) return;  // +-0 (most of a sample's dissipation terms)
    const auto e = static_cast<unsigned>(u >> 52) & 0x7ffu;
    if (e == 0x7ffu) {  // NaN, infinity
      bad_[i] = 1;
      return;
    }
    const std::uint64_t m = (u & ((std::uint64_t{1} << 52) - 1)) | (e ? std::uint64_t{1} << 52 : 0);
    const unsigned ex = e ? e : 1;
    const ExactInt v = static_cast<ExactInt>(m) << (ex & 31u);
    bins_[i * kBins + (ex >> 5)] += (u >> 63) ? -v : v;
  }
  // The sums (over the ranks with r: one collective; every rank gets the same).
  std::vector<double> result(const SumReducer* r = nullptr);

 private:
  std::vector<ExactInt> bins_;
  std::vector<std::uint8_t> bad_;
};

// terms(put) calls put(i, x) for every term x of sum i; the sums, over the ranks with r.
template <class Terms>
std::vector<double> sum_exactly(std::size_t sums, Terms&& terms, const SumReducer* r = nullptr) {
  ExactSums s(sums);
  terms([&s](std::size_t i, double x) { s.add(i, x); });
  return s.result(r);
}

}  // namespace cdem
