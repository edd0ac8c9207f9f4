// Order-free sums (exact_sum.hpp).
#include "cdem/core/exact_sum.hpp"

#include <cmath>
#include <limits>

namespace cdem {

namespace {
constexpr std::int64_t kNoTerms = -(std::int64_t{1} << 40);  // the exponent of a sum without terms
constexpr int kLimbBits = 42;
constexpr std::int64_t kLimbMask = (std::int64_t{1} << kLimbBits) - 1;

int bit_length(std::int64_t n) {
  int b = 0;
  while (n > 0) ++b, n >>= 1;
  return b;
}
}  // namespace

void ExactSums::reset(std::size_t sums) {
  amax_.assign(sums, 0.0);
  f1_.assign(sums, 0.0);
  f2_.assign(sums, 0.0);
  count_.assign(sums, 0);
  scale_.assign(sums, 0);
  bad_.assign(sums, 0);
  skip_.assign(sums, 1);
  acc_.assign(sums, 0);
}

void ExactSums::fix_scales(const SumReducer* r) {
  const std::size_t k = size();
  // per sum: the largest exponent, the largest count, and whether a term was not finite
  std::vector<std::int64_t> v(3 * k);
  for (std::size_t i = 0; i < k; ++i) {
    int e = 0;
    const bool finite = !bad_[i] && amax_[i] <= std::numeric_limits<double>::max();
    if (amax_[i] > 0 && finite) std::frexp(amax_[i], &e);  // amax < 2^e
    v[3 * i] = amax_[i] > 0 && finite ? e : kNoTerms;
    v[3 * i + 1] = count_[i];
    v[3 * i + 2] = finite ? 0 : 1;
  }
  if (r && r->ranks > 1) r->max(v.data(), v.size());
  const std::int64_t ranks = r ? r->ranks : 1;
  for (std::size_t i = 0; i < k; ++i) {
    bad_[i] = v[3 * i + 2] != 0;
    skip_[i] = bad_[i] || v[3 * i] == kNoTerms;
    if (skip_[i]) continue;
    // N <= ranks x the largest count: |sum| < N 2^(e + S) <= 2^125
    const auto s = 125 - v[3 * i] - bit_length(ranks * v[3 * i + 1]);
    scale_[i] = s;
    f1_[i] = std::ldexp(1.0, static_cast<int>(s / 2));
    f2_[i] = std::ldexp(1.0, static_cast<int>(s - s / 2));
  }
}

std::vector<double> ExactSums::result(const SumReducer* r) {
  const std::size_t k = size();
  std::vector<double> out(k, 0.0);
  std::vector<std::int64_t> limbs(3 * k);
  for (std::size_t i = 0; i < k; ++i) {
    const ExactInt a = acc_[i];
    limbs[3 * i] = static_cast<std::int64_t>(a & kLimbMask);
    limbs[3 * i + 1] = static_cast<std::int64_t>((a >> kLimbBits) & kLimbMask);
    limbs[3 * i + 2] = static_cast<std::int64_t>(a >> (2 * kLimbBits));  // (arithmetic: |a| < 2^125)
  }
  if (r && r->ranks > 1) r->sum(limbs.data(), limbs.size());
  for (std::size_t i = 0; i < k; ++i) {
    if (bad_[i]) {
      out[i] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    if (skip_[i]) continue;
    const ExactInt one = 1;
    const ExactInt total = static_cast<ExactInt>(limbs[3 * i + 2]) * (one << (2 * kLimbBits)) +
                           static_cast<ExactInt>(limbs[3 * i + 1]) * (one << kLimbBits) +
                           static_cast<ExactInt>(limbs[3 * i]);
    out[i] = std::ldexp(static_cast<double>(total), static_cast<int>(-scale_[i]));
  }
  return out;
}

}  // namespace cdem
