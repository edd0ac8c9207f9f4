#include "cdem/mesh/mesh_order.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace cdem {
namespace {

constexpr int kBits = 21;  // per axis: 3 x 21 = 63 bits

// The Hilbert keys of `pts` on a grid of kBits bits per axis over their bounding box (an axis of
// zero extent, as z in 2D, maps to 0; a non-finite coordinate, which the mesh checks reject
// before this is reached, to 0 as well).
std::vector<std::uint64_t> keys_of(const std::vector<Vec3>& pts) {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -1.0 * lo;
  for (const Vec3& p : pts) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double top = static_cast<double>((1u << kBits) - 1);
  auto grid = [&](double v, double a, double b) -> std::uint32_t {
    const double s = (v - a) / (b - a);
    if (!(s > 0)) return 0;  // (also NaN and an axis of zero extent)
    return static_cast<std::uint32_t>(std::min(top, std::floor(s * top)));
  };
  std::vector<std::uint64_t> key(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i)
    key[i] = hilbert_key(grid(pts[i].x, lo.x, hi.x), grid(pts[i].y, lo.y, hi.y), grid(pts[i].z, lo.z, hi.z));
  return key;
}

// The indices 0 .. n-1 sorted by key, ties in index order.
std::vector<std::int32_t> order_of(const std::vector<std::uint64_t>& key) {
  std::vector<std::int32_t> ord(key.size());
  std::iota(ord.begin(), ord.end(), 0);
  std::stable_sort(ord.begin(), ord.end(), [&](std::int32_t a, std::int32_t b) { return key[a] < key[b]; });
  return ord;
}

template <class T>
void permute(std::vector<T>& v, const std::vector<std::int32_t>& ord) {
  if (v.size() != ord.size()) return;  // (an optional array left empty)
  std::vector<T> out;
  out.reserve(v.size());
  for (const auto i : ord) out.push_back(v[static_cast<std::size_t>(i)]);
  v.swap(out);
}

}  // namespace

std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  std::uint32_t X[3] = {x, y, z};
  const std::uint32_t M = 1u << (kBits - 1);
  // inverse undo
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) {
    const std::uint32_t P = Q - 1;
    for (int i = 0; i < 3; ++i) {
      if (X[i] & Q) {
        X[0] ^= P;  // invert
      } else {      // exchange
        const std::uint32_t t = (X[0] ^ X[i]) & P;
        X[0] ^= t;
        X[i] ^= t;
      }
    }
  }
  // Gray encode
  for (int i = 1; i < 3; ++i) X[i] ^= X[i - 1];
  std::uint32_t t = 0;
  for (std::uint32_t Q = M; Q > 1; Q >>= 1)
    if (X[2] & Q) t ^= Q - 1;
  for (int i = 0; i < 3; ++i) X[i] ^= t;
  std::uint64_t key = 0;
  for (int b = kBits - 1; b >= 0; --b)
    for (int i = 0; i < 3; ++i) key = (key << 1) | ((X[i] >> b) & 1u);
  return key;
}

void order_mesh_spatially(Mesh& mesh) {
  const std::size_t nv = mesh.vertices.size(), ne = mesh.num_elements();
  if (nv == 0 || ne == 0) return;
  // vertices
  const std::vector<std::int32_t> vord = order_of(keys_of(mesh.vertices));
  std::vector<std::int32_t> vnew(nv);
  for (std::size_t k = 0; k < nv; ++k) vnew[static_cast<std::size_t>(vord[k])] = static_cast<std::int32_t>(k);
  permute(mesh.vertices, vord);
  auto renumber = [&](std::int32_t v) {
    return v >= 0 && static_cast<std::size_t>(v) < nv ? vnew[static_cast<std::size_t>(v)] : v;
  };
  for (auto& ev : mesh.elem_vertices)
    for (auto& v : ev) v = renumber(v);
  for (auto& fs : mesh.face_sets)
    for (auto& f : fs.facets)
      for (auto& v : f.v) v = renumber(v);
  // elements, by their centroids (in the new vertex numbers)
  std::vector<Vec3> centroid(ne);
  for (std::size_t e = 0; e < ne; ++e) {
    const int k = nodes_of(mesh.elem_type[e]);
    for (int j = 0; j < k; ++j) centroid[e] += mesh.vertices[static_cast<std::size_t>(mesh.elem_vertices[e][j])];
    centroid[e] = (1.0 / k) * centroid[e];
  }
  const std::vector<std::int32_t> eord = order_of(keys_of(centroid));
  permute(mesh.elem_type, eord);
  permute(mesh.elem_vertices, eord);
  permute(mesh.elem_region, eord);
  permute(mesh.elem_tag, eord);
}

}  // namespace cdem
