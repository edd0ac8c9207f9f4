// Blasting funnel measures; the procedure is stated in funnel.hpp and
// docs/theory_fragments.md.
#include "cdem/analysis/funnel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cdem {

namespace {

// Relative tolerance on the geometric tests, so that lattice constructions whose blocks end
// exactly on a station or at exactly 1.5 h from an axis are not at the mercy of rounding.
constexpr double kTol = 1e-9;

double median(std::vector<double> v) {
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  const double upper = v[m];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m));
  return 0.5 * (lower + upper);
}

// The footage of one hole: walk the axis in steps of h/2 until the first station that no
// broken block near the axis covers.
double hole_footage(const FunnelInput& in, std::span<const std::int32_t> broken,
                    std::span<const double> side, double h, Vec3 collar, Vec3 dir) {
  const double step = 0.5 * h;
  const double radius = 1.5 * h * (1.0 + kTol);
  std::vector<char> covered;
  for (const std::int32_t i : broken) {
    const Vec3 rel = in.centroid[i] - collar;
    const double s = dot(rel, dir);
    if (norm(rel - s * dir) > radius) continue;
    const double lo = (s - 0.5 * side[i]) / step, hi = (s + 0.5 * side[i]) / step;
    if (!std::isfinite(lo) || !std::isfinite(hi)) continue;  // a non-finite state (unstable run)
    if (hi < -kTol) continue;  // behind the collar
    const auto k_lo = static_cast<std::int64_t>(std::max(0.0, std::ceil(lo - kTol)));
    const auto k_hi = static_cast<std::int64_t>(std::floor(hi + kTol));
    if (k_hi < k_lo) continue;
    if (static_cast<std::size_t>(k_hi) >= covered.size())
      covered.resize(static_cast<std::size_t>(k_hi) + 1, 0);
    std::fill(covered.begin() + k_lo, covered.begin() + k_hi + 1, 1);
  }
  std::size_t k = 0;
  while (k < covered.size() && covered[k]) ++k;
  return k == 0 ? 0.0 : static_cast<double>(k - 1) * step;
}

}  // namespace

Funnel blasting_funnel(const FunnelInput& in) {
  if (in.dim != 2 && in.dim != 3)
    throw std::invalid_argument("blasting_funnel: dim must be 2 or 3, got " +
                                std::to_string(in.dim));
  const std::size_t n = in.centroid.size();
  if (in.volume.size() != n || in.damage.size() != n || in.fragment_of_block.size() != n)
    throw std::invalid_argument(
        "blasting_funnel: volume, damage and fragment_of_block "
        "must have as many entries as centroid (" +
        std::to_string(n) + ")");
  const Vec3 up = normalized(in.up);
  if (norm(up) == 0.0) throw std::invalid_argument("blasting_funnel: `up` is the zero vector");

  Funnel out;
  out.footage_per_hole.assign(in.holes.size(), 0.0);
  if (n == 0) return out;

  // Block sides s_i = V^(1/dim) and the typical size h (their median).
  std::vector<double> side(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double v = std::max(in.volume[i], 0.0);
    side[i] = in.dim == 2 ? std::sqrt(v) : std::cbrt(v);
  }
  const double h = median(side);
  if (!(h > 0.0 && std::isfinite(h)))
    throw std::invalid_argument("blasting_funnel: the typical block size is not positive");
  out.typical_size = h;

  // Horizontal axes x' (from x_axis, or y if x_axis is parallel to up) and y' = up x x'.
  auto horizontal = [&](Vec3 a) { return a - dot(a, up) * up; };
  Vec3 ex = normalized(horizontal(in.x_axis));
  if (norm(horizontal(in.x_axis)) <= 1e-6 * norm(in.x_axis))
    ex = normalized(horizontal(Vec3{0, 1, 0}));
  const Vec3 ey = cross(up, ex);

  std::vector<std::int32_t> broken;
  double x_min = std::numeric_limits<double>::infinity(), x_max = -x_min;
  double y_min = x_min, y_max = -x_min;
  for (std::size_t i = 0; i < n; ++i) {
    const bool is_broken =
        in.fragment_of_block[i] != in.main_fragment || in.damage[i] >= in.damage_threshold;
    if (!is_broken) continue;
    broken.push_back(static_cast<std::int32_t>(i));
    ++out.broken_blocks;
    out.broken_volume += in.volume[i];
    const Vec3 c = in.centroid[i];
    const double half = 0.5 * side[i];
    const double depth_c = in.surface_level - dot(c, up);  // centroid depth below the surface
    out.depth = std::max(out.depth, depth_c + half);
    if (depth_c <= h * (1.0 + kTol)) {  // top layer
      const double x = dot(c, ex), y = dot(c, ey);
      x_min = std::min(x_min, x - half);
      x_max = std::max(x_max, x + half);
      y_min = std::min(y_min, y - half);
      y_max = std::max(y_max, y + half);
    }
  }
  if (x_max >= x_min) {
    out.l_x = x_max - x_min;
    out.l_y = in.dim == 3 ? y_max - y_min : 0.0;
    out.axial_ratio = out.l_x > 0.0 ? out.l_y / out.l_x : 0.0;
  }

  for (std::size_t k = 0; k < in.holes.size(); ++k) {
    const Vec3 dir = normalized(in.holes[k].second);
    if (norm(dir) == 0.0)
      throw std::invalid_argument("blasting_funnel: hole " + std::to_string(k) +
                                  " has a zero direction");
    out.footage_per_hole[k] = hole_footage(in, broken, side, h, in.holes[k].first, dir);
  }
  if (!in.holes.empty()) {
    double sum = 0.0;
    for (const double f : out.footage_per_hole) sum += f;
    out.footage = sum / static_cast<double>(in.holes.size());
  }
  return out;
}

}  // namespace cdem
