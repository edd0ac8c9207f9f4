// Fragments by union-find over intact bonds, and their sizes (SPEC 4, eq. 17).
// See docs/theory_fragments.md.
#include "cdem/analysis/fragments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

namespace cdem {

namespace {

// Disjoint-set forest (Tarjan): union by size and full path compression give an amortised
// cost of alpha(n) per operation. Sequential on purpose: the labelling below does not depend
// on the union order, so the result is the same on any number of threads.
class DisjointSets {
 public:
  explicit DisjointSets(std::int32_t n)
      : parent_(static_cast<std::size_t>(n)), size_(static_cast<std::size_t>(n), 1) {
    std::iota(parent_.begin(), parent_.end(), std::int32_t{0});
  }

  std::int32_t find(std::int32_t x) {
    std::int32_t root = x;
    while (parent_[root] != root) root = parent_[root];
    while (parent_[x] != root) {  // second pass: point the whole path at the root
      const std::int32_t next = parent_[x];
      parent_[x] = root;
      x = next;
    }
    return root;
  }

  void unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

 private:
  std::vector<std::int32_t> parent_;
  std::vector<std::int32_t> size_;
};

// Running sums of one fragment, accumulated in increasing block order (deterministic).
struct Accumulator {
  double volume = 0;
  Vec3 vol_centroid{}, vol_velocity{};  // sums of V_i c_i and V_i v_i
  Vec3 sum_centroid{}, sum_velocity{};  // plain sums (fallback for a zero-volume fragment)
  Vec3 bbox_min{}, bbox_max{};
  std::int32_t blocks = 0;
};

Vec3 min3(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
Vec3 max3(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

void check_input(const BlockGeometry& g, int dim) {
  if (dim != 2 && dim != 3)
    throw std::invalid_argument("find_fragments: dim must be 2 or 3, got " + std::to_string(dim));
  const std::size_t n = g.volume.size();
  if (g.bbox_min.size() != n || g.bbox_max.size() != n || g.centroid.size() != n ||
      g.velocity.size() != n)
    throw std::invalid_argument(
        "find_fragments: bbox_min, bbox_max, centroid and velocity "
        "must have as many entries as volume (" +
        std::to_string(n) + ")");
  if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("find_fragments: more blocks than an int32 index can hold");
  for (std::size_t i = 0; i < n; ++i)
    if (!(std::isfinite(g.volume[i]) && g.volume[i] >= 0.0))
      throw std::invalid_argument("find_fragments: block " + std::to_string(i) +
                                  " has a negative or non-finite volume");
}

}  // namespace

double characteristic_size(double volume, double l_max, int dim) {
  // Eq. 17: the mean of the equivalent cube side V^(1/3) and the longest box side. In 2D the
  // "volume" is area x 1 m, and the equivalent square side A^(1/2) takes the cube's place.
  const double equivalent_side = dim == 2 ? std::sqrt(volume) : std::cbrt(volume);
  return 0.5 * (equivalent_side + l_max);
}

FragmentResult find_fragments(const BlockGeometry& g, std::span<const Bond> bonds, int dim) {
  check_input(g, dim);
  const auto n = static_cast<std::int32_t>(g.volume.size());

  DisjointSets sets(n);
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const Bond& bd = bonds[k];
    if (bd.a < 0 || bd.a >= n || bd.b < 0 || bd.b >= n)
      throw std::invalid_argument("find_fragments: bond " + std::to_string(k) + " (" +
                                  std::to_string(bd.a) + ", " + std::to_string(bd.b) +
                                  ") refers to a block outside 0.." + std::to_string(n - 1));
    sets.unite(bd.a, bd.b);
  }

  // Provisional labels in order of each set's smallest block index, then the sums.
  std::vector<std::int32_t> label_of_root(static_cast<std::size_t>(n), -1);
  std::vector<std::int32_t> label(static_cast<std::size_t>(n));
  std::vector<Accumulator> acc;
  for (std::int32_t i = 0; i < n; ++i) {
    const std::int32_t r = sets.find(i);
    if (label_of_root[r] < 0) {
      label_of_root[r] = static_cast<std::int32_t>(acc.size());
      Accumulator a;
      a.bbox_min = g.bbox_min[i];
      a.bbox_max = g.bbox_max[i];
      acc.push_back(a);
    }
    const std::int32_t l = label_of_root[r];
    label[i] = l;
    Accumulator& a = acc[l];
    const double v = g.volume[i];
    a.volume += v;
    a.vol_centroid += v * g.centroid[i];
    a.vol_velocity += v * g.velocity[i];
    a.sum_centroid += g.centroid[i];
    a.sum_velocity += g.velocity[i];
    a.bbox_min = min3(a.bbox_min, g.bbox_min[i]);
    a.bbox_max = max3(a.bbox_max, g.bbox_max[i]);
    ++a.blocks;
  }

  // Final ids: decreasing volume; equal volumes keep the provisional (smallest block) order.
  const auto k = static_cast<std::int32_t>(acc.size());
  std::vector<std::int32_t> order(static_cast<std::size_t>(k));
  std::iota(order.begin(), order.end(), std::int32_t{0});
  std::sort(order.begin(), order.end(), [&](std::int32_t p, std::int32_t q) {
    if (acc[p].volume != acc[q].volume) return acc[p].volume > acc[q].volume;
    return p < q;
  });
  std::vector<std::int32_t> id_of_label(static_cast<std::size_t>(k));
  for (std::int32_t j = 0; j < k; ++j) id_of_label[order[j]] = j;

  FragmentResult res;
  res.fragment_of_block.resize(static_cast<std::size_t>(n));
  for (std::int32_t i = 0; i < n; ++i) res.fragment_of_block[i] = id_of_label[label[i]];

  const int axes = dim == 2 ? 2 : 3;  // 2D: the z side of the box is not a length of the body
  res.fragments.resize(static_cast<std::size_t>(k));
  for (std::int32_t j = 0; j < k; ++j) {
    const Accumulator& a = acc[order[j]];
    Fragment& f = res.fragments[j];
    f.volume = a.volume;
    f.bbox_min = a.bbox_min;
    f.bbox_max = a.bbox_max;
    f.l_max = 0.0;
    for (int d = 0; d < axes; ++d) f.l_max = std::max(f.l_max, a.bbox_max[d] - a.bbox_min[d]);
    f.l_bc = characteristic_size(a.volume, f.l_max, dim);
    if (a.volume > 0.0) {
      f.centroid = a.vol_centroid / a.volume;
      f.velocity = a.vol_velocity / a.volume;
    } else {  // degenerate blocks only: plain means
      f.centroid = a.sum_centroid / static_cast<double>(a.blocks);
      f.velocity = a.sum_velocity / static_cast<double>(a.blocks);
    }
    f.blocks = a.blocks;
  }
  return res;
}

std::int32_t largest_fragment_of(const FragmentResult& r, std::span<const std::int32_t> blocks) {
  std::int32_t best = -1;
  for (const std::int32_t b : blocks) {
    if (b < 0 || static_cast<std::size_t>(b) >= r.fragment_of_block.size())
      throw std::invalid_argument("largest_fragment_of: block " + std::to_string(b) +
                                  " is out of range");
    const std::int32_t f = r.fragment_of_block[b];
    if (best < 0 || f < best) best = f;
  }
  return best;
}

}  // namespace cdem
