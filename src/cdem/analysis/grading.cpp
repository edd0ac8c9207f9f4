// Grading curve and d_x sizes; the convention is stated in grading.hpp and
// docs/theory_fragments.md.
#include "cdem/analysis/grading.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace cdem {

Grading grading_curve(std::span<const Fragment> fragments, bool exclude_largest) {
  std::int32_t largest = -1;
  if (exclude_largest)
    for (std::size_t i = 0; i < fragments.size(); ++i)
      if (largest < 0 || fragments[i].volume > fragments[largest].volume)
        largest = static_cast<std::int32_t>(i);
  return grading_curve_excluding(fragments, largest);
}

Grading grading_curve_excluding(std::span<const Fragment> fragments, std::int32_t excluded) {
  if (excluded < -1 || (excluded >= 0 && static_cast<std::size_t>(excluded) >= fragments.size()))
    throw std::invalid_argument("grading_curve: excluded fragment " + std::to_string(excluded) +
                                " is out of range");
  Grading g;
  g.excluded = excluded;

  std::vector<std::int32_t> kept;
  kept.reserve(fragments.size());
  for (std::size_t i = 0; i < fragments.size(); ++i) {
    const Fragment& f = fragments[i];
    if (!(std::isfinite(f.volume) && f.volume >= 0.0 && std::isfinite(f.l_bc)))
      throw std::invalid_argument("grading_curve: fragment " + std::to_string(i) +
                                  " has a negative or non-finite volume or size");
    if (static_cast<std::int32_t>(i) != excluded && f.volume > 0.0)
      kept.push_back(static_cast<std::int32_t>(i));
  }
  // Increasing size; equal sizes in index order, so the volume sums are deterministic.
  std::stable_sort(kept.begin(), kept.end(), [&](std::int32_t p, std::int32_t q) {
    return fragments[p].l_bc < fragments[q].l_bc;
  });

  double total = 0.0;
  for (const std::int32_t i : kept) total += fragments[i].volume;
  g.total_volume = total;

  double cumulative = 0.0;
  for (std::size_t j = 0; j < kept.size(); ++j) {
    cumulative += fragments[kept[j]].volume;
    const double s = fragments[kept[j]].l_bc;
    // Fragments of equal size make one point carrying all their volume: passing(L) counts
    // every fragment with L_bc <= L.
    if (j + 1 < kept.size() && fragments[kept[j + 1]].l_bc == s) continue;
    g.size.push_back(s);
    g.passing_pct.push_back(100.0 * cumulative / total);
  }
  if (!g.passing_pct.empty()) g.passing_pct.back() = 100.0;  // exact despite rounding

  for (int j = 0; j < 9; ++j) g.d[j] = size_at_passing(g, 10.0 * (j + 1));
  return g;
}

double size_at_passing(const Grading& g, double pct) {
  if (g.size.empty()) return std::numeric_limits<double>::quiet_NaN();
  if (g.passing_pct.front() >= pct) return g.size.front();
  // First point reaching pct; the last point is 100 %, so it exists for pct <= 100.
  const auto it = std::lower_bound(g.passing_pct.begin(), g.passing_pct.end(), pct);
  if (it == g.passing_pct.end()) return g.size.back();
  const auto i = static_cast<std::size_t>(it - g.passing_pct.begin());
  const double p0 = g.passing_pct[i - 1], p1 = g.passing_pct[i];
  const double s0 = g.size[i - 1], s1 = g.size[i];
  return s0 + (pct - p0) / (p1 - p0) * (s1 - s0);
}

}  // namespace cdem
