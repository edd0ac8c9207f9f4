// Helpers shared by the explosive-model tests (tests/unit/test_bar_charges.cpp and
// tests/verification/test_solid_charge.cpp): holes and decks built in code the way load_case
// places them, a Case holding the built-in emulsion, graded structured grids, an independent
// point-sampling reference for "the elements a bar passes through", and a temporary directory
// for small case files. The meshes, materials and in-code Case come from model_builders.hpp.
#pragma once
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/explosive_library.hpp"
#include "cdem/io/case.hpp"
#include "verification/model_builders.hpp"

namespace cdem::test_charges {

using namespace test_models;

// The built-in emulsion of SPEC 5.1 (Landau: rho 1150, D 5000, Q 3.1e6, gamma1 3, gamma2 1.33).
inline ExplosiveDef emulsion() { return {"emulsion", *builtin_explosive("emulsion")}; }

// One [[hole.charge]] entry: `stemming_before` metres of stemming below the deck (placed from
// the bottom up, as in a case file), then the deck.
struct DeckSpec {
  double length = 0;
  double delay = 0;
  bool initiate_top = false;
  double stemming_before = 0;
  std::string explosive = "emulsion";
};

// A hole from `collar` (top) to `end` (bottom) with its decks placed from the bottom up exactly
// as load_case does (io/case_charges.cpp): deck.bottom = end + s up, deck.top = end + (s + length) up.
inline HoleDef make_hole(const std::string& name, Vec3 collar, Vec3 end, double diameter,
                         const std::vector<DeckSpec>& decks, ChargeModel model = ChargeModel::Bar,
                         double attenuation = 1.25) {
  HoleDef h;
  h.name = name;
  h.collar = collar;
  h.end = end;
  h.diameter = diameter;
  h.model = model;
  h.attenuation_exponent = attenuation;
  // The tests of SPEC 2 and 3's equations (eq. 9's volume, a solid block's own pressure) use the
  // literal gas model; the gas bodies have their own tests (test_gas.cpp) and set it.
  h.gas = GasModel::Literal;
  const Vec3 up = normalized(collar - end);
  double s = 0;
  for (const auto& ds : decks) {
    if (ds.stemming_before > 0) {
      h.stemming.emplace_back(s, s + ds.stemming_before);
      s += ds.stemming_before;
    }
    Deck d;
    d.explosive = ds.explosive;
    d.length = ds.length;
    d.delay = ds.delay;
    d.initiate_top = ds.initiate_top;
    d.bottom = end + s * up;
    d.top = end + (s + ds.length) * up;
    s += ds.length;
    h.decks.push_back(d);
  }
  return h;
}

// A single-deck bar from `bottom` to `top` (the hole is exactly the charge).
inline HoleDef bar(const std::string& name, Vec3 bottom, Vec3 top, double diameter,
                   double delay = 0, bool initiate_top = false, double attenuation = 1.25) {
  return make_hole(name, top, bottom, diameter, {{norm(top - bottom), delay, initiate_top, 0.0}},
                   ChargeModel::Bar, attenuation);
}

// A Case for in-code runs with the emulsion available and the given holes.
inline Case charge_case(const std::vector<BlockMaterial>& mats,
                        const std::vector<InterfaceMaterial>& ifaces,
                        const std::vector<HoleDef>& holes) {
  Case c = make_case(mats, ifaces);
  c.path = "in-code charge case";
  c.explosives = {emulsion()};
  c.holes = holes;
  return c;
}

// A structured quadrilateral grid on the given (increasing) x and y lines: cells may differ in
// size (graded meshes for the segmentation test).
inline Mesh graded_quad_grid(const std::vector<double>& xs, const std::vector<double>& ys,
                             const std::string& region = "rock") {
  Mesh m;
  m.dim = 2;
  m.region_names = {region};
  const int nx = static_cast<int>(xs.size()) - 1, ny = static_cast<int>(ys.size()) - 1;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.vertices.push_back({xs[i], ys[j], 0.0});
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.elem_type.push_back(ElemType::Quad4);
      m.elem_vertices.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)});
      m.elem_region.push_back(0);
      m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
    }
  add_box_face_sets(m);
  return m;
}

// Removes the elements whose centroid satisfies `pred` (a void in the mesh). Vertices stay.
template <class Pred>
void remove_elements(Mesh& mesh, Pred pred) {
  Mesh out = mesh;
  out.elem_type.clear();
  out.elem_vertices.clear();
  out.elem_region.clear();
  out.elem_tag.clear();
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) {
    Vec3 c{};
    const int k = nodes_of(mesh.elem_type[e]);
    for (int i = 0; i < k; ++i) c += mesh.vertices[mesh.elem_vertices[e][i]];
    if (pred(c / k)) continue;
    out.elem_type.push_back(mesh.elem_type[e]);
    out.elem_vertices.push_back(mesh.elem_vertices[e]);
    out.elem_region.push_back(mesh.elem_region[e]);
    out.elem_tag.push_back(mesh.elem_tag[e]);
  }
  out.face_sets.clear();
  add_box_face_sets(out);
  mesh = std::move(out);
}

// Reference (undeformed) centroid of block b.
inline Vec3 centroid0(const Model& m, std::int32_t b) {
  Vec3 c{};
  const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
  for (auto n = n0; n < n1; ++n) c += m.X(n);
  return c / (n1 - n0);
}

// Current signed measure (area x 1 m in 2D, volume in 3D) of block b.
inline double current_measure(const Model& m, std::int32_t b) {
  const int nn = nodes_of(m.block_type[b]);
  std::array<Vec3, 4> p{};
  for (int k = 0; k < nn; ++k) p[k] = m.x[m.block_first_node[b] + k];
  return signed_measure(m.block_type[b], std::span<const Vec3>(p.data(), nn));
}

// Blocks whose reference centroid satisfies `pred`.
template <class Pred>
std::set<std::int32_t> blocks_where(const Model& m, Pred pred) {
  std::set<std::int32_t> s;
  for (std::size_t b = 0; b < m.n_blocks(); ++b)
    if (pred(centroid0(m, static_cast<std::int32_t>(b)))) s.insert(static_cast<std::int32_t>(b));
  return s;
}

// Blocks bound to segment j, and to any segment of bar k.
inline std::set<std::int32_t> segment_blocks(const BarCharges& bc, std::size_t j) {
  return {bc.seg_elem.begin() + bc.seg_elem_offset[j],
          bc.seg_elem.begin() + bc.seg_elem_offset[j + 1]};
}
inline std::set<std::int32_t> bar_blocks(const BarCharges& bc, std::size_t k) {
  std::set<std::int32_t> s;
  for (auto j = bc.bars[k].seg_begin; j < bc.bars[k].seg_end; ++j) {
    const auto sj = segment_blocks(bc, static_cast<std::size_t>(j));
    s.insert(sj.begin(), sj.end());
  }
  return s;
}

// Whether point p lies in block b (reference geometry), with a relative tolerance `tol` on the
// barycentric / edge coordinates: an independent test (no face clipping) for the binding
// reference. Quads are split into the triangles (0, 1, 2) and (0, 2, 3); tets by barycentric
// coordinates.
inline bool point_in_block(const Model& m, std::int32_t b, Vec3 p, double tol) {
  const auto n0 = m.block_first_node[b];
  auto in_tri = [&](Vec3 a, Vec3 bb, Vec3 c) {
    const double area = cross(bb - a, c - a).z;
    const double l0 = cross(bb - p, c - p).z / area, l1 = cross(c - p, a - p).z / area;
    const double l2 = 1.0 - l0 - l1;
    return l0 >= -tol && l1 >= -tol && l2 >= -tol;
  };
  switch (m.block_type[b]) {
    case ElemType::Tri3:
      return in_tri(m.X(n0), m.X(n0 + 1), m.X(n0 + 2));
    case ElemType::Quad4:
      return in_tri(m.X(n0), m.X(n0 + 1), m.X(n0 + 2)) || in_tri(m.X(n0), m.X(n0 + 2), m.X(n0 + 3));
    case ElemType::Tet4: {
      const Vec3 a = m.X(n0), e1 = m.X(n0 + 1) - a, e2 = m.X(n0 + 2) - a, e3 = m.X(n0 + 3) - a;
      const double v = dot(e1, cross(e2, e3));
      const Vec3 q = p - a;
      const double l1 = dot(q, cross(e2, e3)) / v, l2 = dot(e1, cross(q, e3)) / v,
                   l3 = dot(e1, cross(e2, q)) / v;
      return l1 >= -tol && l2 >= -tol && l3 >= -tol && 1.0 - l1 - l2 - l3 >= -tol;
    }
  }
  return false;
}

// The reference answer to "which elements does the segment a-b pass through": the blocks that
// contain at least one of `samples` points drawn uniformly at random along the open segment
// (barycentric tolerance 1e-9). A block the segment crosses over a length l is hit with
// probability 1 - (1 - l / L)^samples (certain for l >> L / samples); a block it only touches at
// one point (a corner, an edge crossing) is hit only within ~1e-9 of its size of that point,
// i.e. never. Points on a shared face or edge hit every block around it (the tolerance).
inline std::set<std::int32_t> sampled_crossed_blocks(const Model& m, Vec3 a, Vec3 b, int samples,
                                                     unsigned seed = 12345) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::set<std::int32_t> s;
  for (int i = 0; i < samples; ++i) {
    const Vec3 p = a + u(gen) * (b - a);
    for (std::size_t e = 0; e < m.n_blocks(); ++e)
      if (point_in_block(m, static_cast<std::int32_t>(e), p, 1e-9))
        s.insert(static_cast<std::int32_t>(e));
  }
  return s;
}

// Runs the enclosing scope on one OpenMP thread (restored at the end). Results do not depend on
// the thread count (ARCHITECTURE: bitwise identical); on a shared, loaded 2-core machine the
// barriers of a 2-thread team on a 400-block model cost 100x the work (15 s instead of 0.1 s).
class SingleThread {
 public:
  SingleThread() : saved_(omp_get_max_threads()) { omp_set_num_threads(1); }
  ~SingleThread() { omp_set_num_threads(saved_); }
  SingleThread(const SingleThread&) = delete;
  SingleThread& operator=(const SingleThread&) = delete;

 private:
  int saved_;
};

// A temporary directory removed with its contents at the end of the scope.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("cdem_" + tag + "_" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  // Writes `text` to the file `name` in the directory and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = path_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace cdem::test_charges
