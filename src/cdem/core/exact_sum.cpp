// Order-free sums (exact_sum.hpp).
#include "cdem/core/exact_sum.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace cdem {

namespace {

__extension__ typedef unsigned __int128 ExactUInt;
constexpr int kLimbBits = 42;
constexpr std::int64_t kLimbMask = (std::int64_t{1} << kLimbBits) - 1;
constexpr int kBins = ExactSums::kBins;

// The bins carried into 32-bit digits d[0, kBins) (each in [0, 2^32)); returns the carry out of
// the last, the digits above them (its sign is the sum's). No overflow while every bin is below
// 2^126 (2^42 terms): a carry is below 2^95.
ExactInt carry_digits(const ExactInt* bins, std::uint32_t* d, bool negate) {
  ExactInt carry = 0;
  for (int k = 0; k < kBins; ++k) {
    const ExactInt t = (negate ? -bins[k] : bins[k]) + carry;
    d[k] = static_cast<std::uint32_t>(t & 0xffffffff);
    carry = t >> 32;  // (arithmetic: t = carry 2^32 + d[k])
  }
  return carry;
}

// The exact value sum_k bins[k] 2^(32 k - 1075), rounded to the nearest double (ties to even).
double round_bins(const ExactInt* bins) {
  std::uint32_t d[kBins + 4] = {};
  ExactInt top = carry_digits(bins, d, false);
  const bool negative = top < 0;
  if (negative) top = carry_digits(bins, d, true);
  // the carry out (below 2^95, >= 0 now) as the digits above the bins'
  for (int k = 0; k < 4; ++k) d[kBins + k] = static_cast<std::uint32_t>((top >> (32 * k)) & 0xffffffff);
  int t = kBins + 3;
  while (t >= 0 && d[t] == 0) --t;
  if (t < 0) return 0.0;
  // the 128 bits from digit t down, shifted so that the top bit is bit 127; the 64 above, with
  // every bit below them or'ed into their last (the sticky bit: the conversion to double then
  // rounds to nearest, ties to even, as the whole number would)
  ExactUInt x = 0;
  for (int k = t; k > t - 4; --k) x = (x << 32) | (k >= 0 ? d[k] : 0u);
  const int lz = std::countl_zero(d[t]);
  x <<= lz;
  auto hi = static_cast<std::uint64_t>(x >> 64);
  bool sticky = static_cast<std::uint64_t>(x) != 0;
  for (int k = 0; k < t - 3 && !sticky; ++k) sticky = d[k] != 0;
  hi |= sticky ? 1u : 0u;
  const double v = std::ldexp(static_cast<double>(hi), 32 * (t - 3) + 64 - lz - 1075);
  return negative ? -v : v;
}

}  // namespace

std::vector<double> ExactSums::result(const SumReducer* r) {
  const std::size_t k = size();
  if (r && r->ranks > 1) {
    // per sum: its bins as three limbs each, then its flag
    const std::size_t per = 3 * kBins + 1;
    std::vector<std::int64_t> v(per * k);
    for (std::size_t i = 0; i < k; ++i) {
      std::int64_t* p = v.data() + per * i;
      for (int b = 0; b < kBins; ++b) {
        const ExactInt a = bins_[i * kBins + static_cast<std::size_t>(b)];
        p[3 * b] = static_cast<std::int64_t>(a & kLimbMask);
        p[3 * b + 1] = static_cast<std::int64_t>((a >> kLimbBits) & kLimbMask);
        p[3 * b + 2] = static_cast<std::int64_t>(a >> (2 * kLimbBits));  // (arithmetic: |a| < 2^126)
      }
      p[3 * kBins] = bad_[i];
    }
    r->sum(v.data(), v.size());
    for (std::size_t i = 0; i < k; ++i) {
      const std::int64_t* p = v.data() + per * i;
      for (int b = 0; b < kBins; ++b)
        bins_[i * kBins + static_cast<std::size_t>(b)] = static_cast<ExactInt>(p[3 * b + 2]) * (ExactInt{1} << (2 * kLimbBits)) +
                                                         static_cast<ExactInt>(p[3 * b + 1]) * (ExactInt{1} << kLimbBits) +
                                                         static_cast<ExactInt>(p[3 * b]);
      bad_[i] = p[3 * kBins] != 0;
    }
  }
  std::vector<double> out(k);
  for (std::size_t i = 0; i < k; ++i)
    out[i] = bad_[i] ? std::numeric_limits<double>::quiet_NaN() : round_bins(bins_.data() + i * kBins);
  return out;
}

}  // namespace cdem
