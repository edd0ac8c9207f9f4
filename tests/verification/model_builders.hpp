// Helpers shared by the verification tests of the CDEM core: small structured meshes built in
// code (quad and triangle grids, a tetrahedral box of cubes split into 6 positive tets),
// material value types, a Case for in-code Simulation runs, and small tensor utilities
// (rotations, imposed homogeneous maps x = c + A (X - c), Voigt conversions).
#pragma once
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/io/case.hpp"
#include "cdem/mesh/element_geometry.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/mesh/structured.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/model/materials.hpp"
#include "cdem/model/model.hpp"

namespace cdem::test_models {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------------

inline BlockMaterial rock(double youngs = 1e10, double poisson = 0.25, double density = 2500,
                          const std::string& region = "rock") {
  BlockMaterial m;
  m.name = "rock_" + region;
  m.density = density;
  m.youngs = youngs;
  m.poisson = poisson;
  m.regions = {region};
  return m;
}

// A default interface material (applies to every region pair) of the given law.
inline InterfaceMaterial interface_of(InterfaceLaw law, double ft = 5e6, double c = 15e6,
                                      double phi_deg = 30, double stiffness_factor = 10) {
  InterfaceMaterial im;
  im.name = std::string("bond_") + name_of(law);
  im.law = law;
  im.tensile_strength = ft;
  im.cohesion = c;
  im.friction_deg = phi_deg;
  im.stiffness_factor = stiffness_factor;
  im.is_default = true;
  return im;
}

// ---------------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------------

// nx x ny quadrilaterals (counter-clockwise) of size lx/nx x ly/ny from `origin`, one region.
inline Mesh quad_grid(int nx, int ny, double lx, double ly, Vec3 origin = {},
                      const std::string& region = "rock") {
  Mesh m;
  m.dim = 2;
  m.region_names = {region};
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.vertices.push_back({origin.x + lx * i / nx, origin.y + ly * j / ny, 0.0});
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

// The same grid with every cell split into two counter-clockwise triangles along the diagonal
// (i, j) - (i+1, j+1).
inline Mesh tri_grid(int nx, int ny, double lx, double ly, Vec3 origin = {},
                     const std::string& region = "rock") {
  Mesh m;
  m.dim = 2;
  m.region_names = {region};
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.vertices.push_back({origin.x + lx * i / nx, origin.y + ly * j / ny, 0.0});
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      for (const auto& t :
           {std::array<std::int32_t, 4>{vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), -1},
            std::array<std::int32_t, 4>{vid(i, j), vid(i + 1, j + 1), vid(i, j + 1), -1}}) {
        m.elem_type.push_back(ElemType::Tri3);
        m.elem_vertices.push_back(t);
        m.elem_region.push_back(0);
        m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
      }
    }
  add_box_face_sets(m);
  return m;
}

// nx x ny x nz cubes (cells lx/nx x ly/ny x lz/nz) from `origin`, each split into the 6 tets of
// the Kuhn (Freudenthal) triangulation: tet p = (000, e_p0, e_p0 + e_p1, 111) for each
// permutation p of the axes. The same split in every cell makes the mesh conforming (a shared
// cube face is cut along the same diagonal from both sides). Odd permutations give negative
// volumes; their nodes 1 and 2 are swapped so that every tet is positive (right-handed).
inline Mesh tet_box(int nx, int ny, int nz, double lx, double ly, double lz, Vec3 origin = {},
                    const std::string& region = "rock") {
  return structured_tet_box(nx, ny, nz, {lx, ly, lz}, origin, region);
}

// A single element of the given vertices (counter-clockwise in 2D, positive in 3D).
inline Mesh single_element(ElemType type, const std::vector<Vec3>& pts,
                           const std::string& region = "rock") {
  Mesh m;
  m.dim = type == ElemType::Tet4 ? 3 : 2;
  m.region_names = {region};
  m.vertices = pts;
  std::array<std::int32_t, 4> v{-1, -1, -1, -1};
  for (int i = 0; i < nodes_of(type); ++i) v[i] = i;
  m.elem_type = {type};
  m.elem_vertices = {v};
  m.elem_region = {0};
  m.elem_tag = {1};
  add_box_face_sets(m);
  return m;
}

// Gives the elements whose centroid satisfies `pred` the region `name` (added to the mesh).
template <class Pred>
void assign_region(Mesh& mesh, const std::string& name, Pred pred) {
  const auto r = static_cast<std::int32_t>(mesh.region_names.size());
  mesh.region_names.push_back(name);
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) {
    Vec3 c{};
    const int k = nodes_of(mesh.elem_type[e]);
    for (int i = 0; i < k; ++i) c += mesh.vertices[mesh.elem_vertices[e][i]];
    if (pred(c / k)) mesh.elem_region[e] = r;
  }
}

// The two ends of a bar along x (the free-free vibration tests): its nodes at the smallest and
// the largest reference x, and its length between them; length_change(m) is the mean x of the
// right end less that of the left, less the rest length.
struct BarEnds {
  double x0 = 1e300, len = 0;
  std::vector<std::int32_t> left, right;
  explicit BarEnds(const Model& m) {
    double x1 = -1e300;
    for (const auto& p : m.X_nodes()) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
    len = x1 - x0;
    for (std::size_t n = 0; n < m.n_nodes(); ++n) {
      if (m.X(n).x < x0 + 1e-9) left.push_back(static_cast<std::int32_t>(n));
      if (m.X(n).x > x1 - 1e-9) right.push_back(static_cast<std::int32_t>(n));
    }
  }
  double length_change(const Model& m) const {
    double a = 0, b = 0;
    for (auto n : left) a += m.x[n].x;
    for (auto n : right) b += m.x[n].x;
    return b / right.size() - a / left.size() - len;
  }
};

// Two arrays equal bit for bit (memcmp): the vectorised kernels against their references.
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

inline Model make_model(const Mesh& mesh, const BlockMaterial& mat, const InterfaceMaterial& im) {
  return build_model(mesh, {mat}, {im}, "in-code test model");
}

// A Case for an in-code Simulation: no mesh (the Model is given), no boundaries, no gravity.
inline Case make_case(const std::vector<BlockMaterial>& mats,
                      const std::vector<InterfaceMaterial>& ifaces, double dt_safety = 0.5) {
  Case c;
  c.path = "in-code test case";
  c.title = "verification";
  c.dt_safety = dt_safety;
  c.materials = mats;
  c.interfaces = ifaces;
  if (const char* e = std::getenv("CDEM_TEST_MODE"); e && std::string(e) == "springs") c.interface_mode = InterfaceMode::Springs;
  return c;
}

// Runs the enclosed code with `n` OpenMP threads and restores the previous setting. The kernel-
// level tests call the parallel kernels tens of thousands of times on a handful of elements;
// with one thread they do not depend on how busy the (shared) machine is. Thread independence
// itself is checked by test_determinism.cpp.
class ScopedThreads {
 public:
  explicit ScopedThreads(int n) : saved_(omp_get_max_threads()) { omp_set_num_threads(n); }
  ~ScopedThreads() { omp_set_num_threads(saved_); }
  ScopedThreads(const ScopedThreads&) = delete;
  ScopedThreads& operator=(const ScopedThreads&) = delete;

 private:
  int saved_;
};

// ---------------------------------------------------------------------------------------------
// Kinematics and tensors
// ---------------------------------------------------------------------------------------------

// Rotation by `angle` (rad) about the unit `axis` (Rodrigues).
inline Mat3 rotation(Vec3 axis, double angle) {
  const Vec3 a = normalized(axis);
  const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
  return Mat3{{t * a.x * a.x + c, t * a.x * a.y - s * a.z, t * a.x * a.z + s * a.y,
               t * a.x * a.y + s * a.z, t * a.y * a.y + c, t * a.y * a.z - s * a.x,
               t * a.x * a.z - s * a.y, t * a.y * a.z + s * a.x, t * a.z * a.z + c}};
}

// Exact quarter turn about z (no cos(pi/2) round-off).
inline Mat3 quarter_turn_z() { return Mat3{{0, -1, 0, 1, 0, 0, 0, 0, 1}}; }

// x = c + A (X - c) for every node.
inline void apply_map(Model& m, const Mat3& A, Vec3 c = {}) {
  for (std::size_t n = 0; n < m.n_nodes(); ++n) m.x[n] = c + A * (m.X(n) - c);
}

inline Mat3 from_sym6(const Sym6& s) {
  return Mat3{{s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2]}};
}
inline Sym6 to_sym6(const Mat3& a) {
  return {a(0, 0),
          a(1, 1),
          a(2, 2),
          0.5 * (a(0, 1) + a(1, 0)),
          0.5 * (a(1, 2) + a(2, 1)),
          0.5 * (a(0, 2) + a(2, 0))};
}

// Linear-elastic stress of a small strain eps (Voigt, tensor shear components):
// sigma = lambda tr(eps) I + 2 G eps. In 2D (plane strain) eps_zz = 0 and szz = lambda tr(eps).
inline Sym6 hooke(const Sym6& eps, const BlockMaterial& mat) {
  const double lam = mat.lambda(), g = mat.shear();
  const double tr = eps[0] + eps[1] + eps[2];
  return {lam * tr + 2 * g * eps[0],
          lam * tr + 2 * g * eps[1],
          lam * tr + 2 * g * eps[2],
          2 * g * eps[3],
          2 * g * eps[4],
          2 * g * eps[5]};
}

// max_k |a_k - b_k| over the six Voigt components.
inline double max_abs_diff(const Sym6& a, const Sym6& b) {
  double d = 0;
  for (int k = 0; k < 6; ++k) d = std::max(d, std::abs(a[k] - b[k]));
  return d;
}
inline double max_abs(const Sym6& a) {
  double d = 0;
  for (double v : a) d = std::max(d, std::abs(v));
  return d;
}

}  // namespace cdem::test_models
