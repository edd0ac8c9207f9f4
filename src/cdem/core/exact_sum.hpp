// Sums whose bits depend neither on the order of their terms nor on how the terms are split
// among ranks (docs/parallel.md "Exact sums"): the energy balance and the fracture degree of a
// history sample, formed by each rank over what it owns and reduced by two collectives, with the
// bits one process gets.
//
// Each sum is a fixed-point integer (128 bits) at a scale 2^S common to all its terms: every term
// is converted once, x 2^S truncated toward zero (exact for all but its bits below 2^-S), and
// integers add exactly in any order. S is set by the largest term's binary exponent e (|x| <
// 2^e over every rank) and a bound N on the number of terms (every rank's count times the
// ranks): S = 125 - e - bits(N), so the sum of N terms stays below 2^125 and fits. The error is
// at most N 2^-S = 2^(e - 125 + 2 bits(N)) against the largest term: below 2^-70 of it for N up to
// 2^27, where a double's running sum errs by up to N 2^-53 of the total. The result is the
// integer rounded once to a double (to nearest), times 2^-S.
//
// A sum with a NaN or infinite term is NaN on every rank. A zero term adds nothing (and -0 is
// +0: as a plain sum's would be, unless every term is -0).
//
// Two passes over the terms: `see` every term (the largest magnitude and the count), then the
// scales (over the ranks: one max-reduction), then `add` every term, then `result` (over the
// ranks: one sum-reduction of the integers, carried as three 42-bit limbs in int64 so that a
// plain MPI_SUM of up to 2^21 ranks cannot overflow). `sum_exactly` runs both passes over a
// callable that lists the terms.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cdem {

// A 128-bit integer (GCC and Clang; __extension__: not ISO C++).
__extension__ typedef __int128 ExactInt;

// The collectives of a distributed sum: in place over n int64 values, every rank's largest
// (max) and every rank's total (sum); ranks: how many. null (or one rank): a sum of one process.
struct SumReducer {
  void (*max)(std::int64_t* v, std::size_t n) = nullptr;
  void (*sum)(std::int64_t* v, std::size_t n) = nullptr;
  int ranks = 1;
};

class ExactSums {
 public:
  explicit ExactSums(std::size_t sums = 0) { reset(sums); }
  void reset(std::size_t sums);
  std::size_t size() const { return amax_.size(); }

  // Pass 1: every term of sum i.
  void see(std::size_t i, double x) {
    const double a = x < 0 ? -x : x;
    if (a > 0) {
      if (a > amax_[i]) amax_[i] = a;
      ++count_[i];
    } else if (!(a == 0)) {
      bad_[i] = 1;  // NaN
    }
  }
  // Between the passes: the scales, over the ranks with r (one collective).
  void fix_scales(const SumReducer* r);
  // Pass 2: every term of sum i, the same as in pass 1.
  void add(std::size_t i, double x) {
    if (!(x != 0) || skip_[i]) return;
    acc_[i] += static_cast<ExactInt>(x * f1_[i] * f2_[i]);
  }
  // The sums, over the ranks with r (one collective).
  std::vector<double> result(const SumReducer* r);

 private:
  std::vector<double> amax_, f1_, f2_;
  std::vector<std::int64_t> count_, scale_;
  std::vector<std::uint8_t> bad_, skip_;
  std::vector<ExactInt> acc_;
};

// Both passes: terms(put) calls put(i, x) for every term x of sum i, the same terms each time.
template <class Terms>
std::vector<double> sum_exactly(std::size_t sums, Terms&& terms, const SumReducer* r = nullptr) {
  ExactSums s(sums);
  terms([&s](std::size_t i, double x) { s.see(i, x); });
  s.fix_scales(r);
  terms([&s](std::size_t i, double x) { s.add(i, x); });
  return s.result(r);
}

}  // namespace cdem
