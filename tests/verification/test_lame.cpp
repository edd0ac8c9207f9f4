// Verification: the Lame problems, a pressurised cavity in an elastic body, solved to the static
// state by the explicit CDEM solver with mass-proportional damping (SPEC 1.4), blocks joined by
// unbreakable elastic springs (interface law 'elastic').
//
// 2D (plane strain): a circular hole of radius a in a disc of radius b = 20 a, pressure p on the
// hole wall, the outer circle fixed. A quarter of the disc with rollers on the two symmetry
// axes, meshed with a structured log-polar grid of quads: ring radii r_i = a q^i with
// q = exp(dtheta), so every cell is nearly square (radial width r (q - 1) ~ arc r dtheta).
// 3D: a spherical cavity of radius a in a ball of radius b, pressure p on the cavity wall, the
// outer sphere fixed; an octant with rollers on the three symmetry planes, meshed with
// tetrahedra by Gmsh (OpenCASCADE sphere and box booleans, a size field growing with r).
//
// Exact solutions (thick cylinder / thick sphere with u(b) = 0 and sigma_r(a) = -p):
//   2D plane strain: u = A r + B / r,
//     sigma_r = 2 (lambda + G) A - 2 G B / r^2,  sigma_theta = 2 (lambda + G) A + 2 G B / r^2,
//     u(b) = 0 -> A = -B / b^2;  sigma_r(a) = -p -> B = p / (2 G / a^2 + 2 (lambda + G) / b^2).
//     b -> infinity: sigma_r = -p a^2 / r^2, sigma_theta = p a^2 / r^2, u = p a^2 / (2 G r).
//   3D: u = A r + B / r^2,
//     sigma_r = (3 lambda + 2 G) A - 4 G B / r^3,  sigma_t = (3 lambda + 2 G) A + 2 G B / r^3,
//     A = -B / b^3;  B = p / (4 G / a^3 + (3 lambda + 2 G) / b^3).
//     b -> infinity: sigma_r = -p a^3 / r^3, sigma_t = p a^3 / (2 r^3), u = p a^3 / (4 G r^2).
// The finite outer radius is thus taken into account exactly (at b = 20 a it changes u at 2 a by
// about 1 %, the stresses by 0.3 %).
//
// Effect of the interface springs (stiffness factor alpha, k_n = alpha E / h, k_s = k_n G / E):
// a body of blocks and springs is softer than the blocks. Under a uniform stress sigma the
// springs of the faces with unit normal n open by sigma n / k (normal part / k_n, tangential
// part / k_s); smeared over the volume this adds the compliance
//   S_spring = (1 / V) sum over faces of A_f [ (n.s.n) n(x)n / k_n + sym(t_s (x) n) / k_s ]
// (the joint-compliance or "crack tensor" sum; exact when the stress is uniform and the blocks
// can take the jumps compatibly, as in a structured grid).
// - 2D log-polar grid: the faces are the radial and hoop edges of nearly square cells of size h,
//   so S_spring adds 1 / (k_n h) = 1 / (alpha E) to the radial and hoop normal compliances
//   (shear springs are not loaded in this axisymmetric problem). The in-plane response stays
//   isotropic with (plane-strain, eps_zz = 0)
//     1 / (2 (lambda' + G')) = 1 / (2 (lambda + G)) + 1 / (alpha E)   (in-plane bulk)
//     1 / (2 G')             = 1 / (2 G)            + 1 / (alpha E)   (in-plane deviatoric)
//   (the eigenvalues of the 2x2 stiffness [[M, lambda], [lambda, M]], M = lambda + 2 G, on
//   (1, 1) and (1, -1), and 1 / (alpha E) added to both compliance eigenvalues).
// - 3D unstructured tets: with an isotropic distribution of face orientations
//   (<n_i n_j n_k n_l> = (d_ij d_kl + d_ik d_jl + d_il d_jk) / 15) and
//   rho_n = (1 / V) sum A_f / k_n, rho_s = (1 / V) sum A_f / k_s = rho_n E / G:
//     hydrostatic s I: eps = rho_n s <n n> = rho_n s I / 3    -> 1 / K' = 1 / K + rho_n
//     shear tau:       2 eps_12 = tau (4 rho_n / 15 + 2 rho_s / 5)
//                                                            -> 1 / G' = 1 / G + 4 rho_n / 15 + 2 rho_s / 5
//   rho_n is summed over the model's own interfaces. For unstructured meshes the blocks cannot
//   all take the uniform-stress jumps compatibly, so this estimate (a Reuss-type bound) is an
//   upper bound of the added compliance; it is used for the displacement with a tolerance that
//   covers the gap (see the 3D test).
// The stresses of the infinite body do not depend on the material at all; with the finite
// outer radius they depend on it only through the small A terms.
//
// Comparison: block stresses rotated to polar/spherical components at the block centroid and
// averaged over radial bins; radial displacements of the nodes averaged per mesh vertex (the
// mean of the two sides of every spring, i.e. the smeared displacement), averaged over radial
// bins. Results are tabulated in docs/verification_waves_lame.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cdem/io/case.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/mesh/topology.hpp"
#include "cdem/model/materials.hpp"
#include "cdem/solver/simulation.hpp"

namespace cdem {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kE = 10e9, kNu = 0.25, kRho = 2500.0;
constexpr double kP = 1e6;  // Pa; wall strain ~1e-4: geometric non-linearity ~1e-4, negligible

BlockMaterial rock_with_damping(double damping) {
  BlockMaterial m;
  m.name = "rock";
  m.regions = {"rock"};
  m.density = kRho;
  m.youngs = kE;
  m.poisson = kNu;
  m.damping = damping;
  return m;
}

InterfaceMaterial elastic_bond(double alpha) {
  InterfaceMaterial im;
  im.name = "bond";
  im.law = InterfaceLaw::Elastic;
  im.stiffness_factor = alpha;
  im.is_default = true;
  return im;
}

BoundaryCondition bc(const std::string& faces, BoundaryType type, double value = 0,
                     std::vector<std::pair<double, double>> table = {{0.0, 1.0}}) {
  BoundaryCondition b;
  b.faces = faces;
  b.type = type;
  b.value = value;
  b.table.points = std::move(table);
  return b;
}

// Thick-cylinder (dim 2, plane strain) or thick-sphere (dim 3) solution with u(b) = 0,
// sigma_r(a) = -p, for Lame constants lam, g.
struct Lame {
  int dim;
  double a, b, p, lam, g;
  double B() const {
    return dim == 2 ? p / (2 * g / (a * a) + 2 * (lam + g) / (b * b))
                    : p / (4 * g / (a * a * a) + (3 * lam + 2 * g) / (b * b * b));
  }
  double A() const { return dim == 2 ? -B() / (b * b) : -B() / (b * b * b); }
  double u(double r) const { return dim == 2 ? A() * r + B() / r : A() * r + B() / (r * r); }
  double sr(double r) const {
    return dim == 2 ? 2 * (lam + g) * A() - 2 * g * B() / (r * r)
                    : (3 * lam + 2 * g) * A() - 4 * g * B() / (r * r * r);
  }
  double st(double r) const {
    return dim == 2 ? 2 * (lam + g) * A() + 2 * g * B() / (r * r)
                    : (3 * lam + 2 * g) * A() + 2 * g * B() / (r * r * r);
  }
};

// ---------------------------------------------------------------------------------------------
// 2D: quarter disc with a hole, structured log-polar quads
// ---------------------------------------------------------------------------------------------

struct PolarMesh {
  Mesh mesh;
  std::vector<double> radii;  // ring radii r_0 = a .. r_nr = b
};

PolarMesh quarter_annulus(double a, double b, int n_theta) {
  const double dth = 0.5 * kPi / n_theta;
  const int nr = static_cast<int>(std::lround(std::log(b / a) / dth));
  const double q = std::pow(b / a, 1.0 / nr);
  PolarMesh pm;
  Mesh& m = pm.mesh;
  m.dim = 2;
  m.region_names = {"rock"};
  for (int i = 0; i <= nr; ++i) pm.radii.push_back(i == nr ? b : a * std::pow(q, i));
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nr + 1) + i); };
  for (int j = 0; j <= n_theta; ++j) {
    const double th = j * dth;
    // Exact axes at j = 0 and j = n_theta (the rollers' normals come from the facets).
    const double c = j == n_theta ? 0.0 : std::cos(th), s = j == 0 ? 0.0 : std::sin(th);
    for (int i = 0; i <= nr; ++i) m.vertices.push_back({pm.radii[i] * c, pm.radii[i] * s, 0.0});
  }
  for (int j = 0; j < n_theta; ++j)
    for (int i = 0; i < nr; ++i) {
      m.elem_type.push_back(ElemType::Quad4);
      m.elem_vertices.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)});
      m.elem_region.push_back(0);
      m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
    }
  FaceSet hole{"hole", {}}, outer{"outer", {}}, xaxis{"xaxis", {}}, yaxis{"yaxis", {}};
  for (int j = 0; j < n_theta; ++j) {
    hole.facets.push_back({{vid(0, j), vid(0, j + 1), -1}});
    outer.facets.push_back({{vid(nr, j), vid(nr, j + 1), -1}});
  }
  for (int i = 0; i < nr; ++i) {
    xaxis.facets.push_back({{vid(i, 0), vid(i + 1, 0), -1}});
    yaxis.facets.push_back({{vid(i, n_theta), vid(i + 1, n_theta), -1}});
  }
  m.face_sets = {hole, outer, xaxis, yaxis};
  check_mesh(m, "test_lame quarter annulus");
  return pm;
}

struct RadialRow {
  double r;            // bin radius (m)
  double sr, st;       // mean block stresses (Pa)
  double sr_ex, st_ex; // exact, averaged the same way
  double u, u_ex;      // mean vertex radial displacement at r (m), exact
};

struct Lame2DResult {
  std::vector<RadialRow> rings;  // one per ring of blocks (stresses) / ring of vertices (u)
  Lame exact, plain;             // effective-medium solution and the one without springs
  double settle = 0;             // max relative change of u over the last 10 % of the hold
  std::size_t blocks = 0;
  std::int64_t steps = 0;
  double dt = 0, wall_s = 0;
};

Lame2DResult run_lame_2d(double alpha, double b_over_a = 10, int n_theta = 24, double ramp_w = 10, double hold_w = 10) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double a = 0.1, b = b_over_a * a;
  PolarMesh pm = quarter_annulus(a, b, n_theta);

  const BlockMaterial probe = rock_with_damping(0);
  const double cp = probe.cp();
  // Quasi-static loading. The slowest mode of the disc (fixed outside, free hole) has
  // omega_1 ~ pi c_p / (2 (b - a)) (the quarter-wave estimate; the disc's own 2.4 c_p / b is of
  // the same size). Damping c_d = 2 omega_1 damps it critically; every mode then decays at
  // least as fast as exp(-omega_1 t). Ramp over 8 transit times (b - a) / c_p (slow compared
  // with 1 / omega_1), then hold until exp(-omega_1 t) < 1e-5 (the state is checked below).
  const double omega1 = 3.8317 * cp / b;
  const double c_d = 2 * omega1;
  const double t_ramp = ramp_w / omega1, t_end = t_ramp + hold_w / omega1;

  Case c;
  c.path = "test_lame 2D (in-code case)";
  c.title = "lame_2d";
  c.dt_safety = 0.5;
  c.materials = {rock_with_damping(c_d)};
  c.interfaces = {elastic_bond(alpha)};
  c.boundaries = {bc("hole", BoundaryType::Pressure, kP, {{0.0, 0.0}, {t_ramp, 1.0}}),
                  bc("outer", BoundaryType::Fixed), bc("xaxis", BoundaryType::Roller),
                  bc("yaxis", BoundaryType::Roller)};
  Simulation sim(build_model(pm.mesh, c.materials, c.interfaces, c.path), c);
  const Model& m = sim.model();

  // Vertex -> nodes (each mesh vertex was split into one node per block).
  const std::size_t nv = pm.mesh.vertices.size();
  std::vector<std::vector<std::int32_t>> vnodes(nv);
  for (std::size_t n = 0; n < m.n_nodes(); ++n) vnodes[m.node_vertex[n]].push_back(static_cast<std::int32_t>(n));
  const int nr = static_cast<int>(pm.radii.size()) - 1;
  auto ring_u = [&](int i) {  // mean radial displacement of the vertices of ring radius r_i
    double s = 0;
    int cnt = 0;
    for (int j = 0; j <= n_theta; ++j) {
      const auto v = j * (nr + 1) + i;
      const Vec3 X = pm.mesh.vertices[v];
      const Vec3 er = X / norm(X);
      double uv = 0;
      for (auto n : vnodes[v]) uv += dot(m.x[n] - m.X[n], er);
      s += uv / vnodes[v].size();
      ++cnt;
    }
    return s / cnt;
  };

  std::vector<double> u_before;
  bool saved = false;
  while (sim.time() < t_end) {
    if (!saved && sim.time() >= t_end - 0.1 * (t_end - t_ramp)) {
      for (int i = 0; i <= nr; ++i) u_before.push_back(ring_u(i));
      saved = true;
    }
    sim.step();
  }

  Lame2DResult res;
  const double lam = probe.lambda(), g = probe.shear();
  // Effective medium with the springs (header comment).
  const double bulk2 = 1.0 / (1.0 / (2 * (lam + g)) + 1.0 / (alpha * kE));  // 2 (lam' + G')
  const double g2 = 1.0 / (1.0 / (2 * g) + 1.0 / (alpha * kE));             // 2 G'
  res.exact = {2, a, b, kP, 0.5 * bulk2 - 0.5 * g2, 0.5 * g2};
  res.plain = {2, a, b, kP, lam, g};

  // Stresses per ring of blocks; blocks are numbered ring-fastest (i + nr * j).
  std::vector<double> sr(nr, 0), st(nr, 0);
  for (std::size_t blk = 0; blk < m.n_blocks(); ++blk) {
    const auto e = m.block_elem_tag[blk] - 1;
    const int i = static_cast<int>(e % nr);
    Vec3 cen{};
    for (auto n = m.block_first_node[blk]; n < m.block_first_node[blk + 1]; ++n) cen += m.X[n];
    const double th = std::atan2(cen.y, cen.x), cs = std::cos(th), sn = std::sin(th);
    const Sym6& s = m.stress[blk];
    sr[i] += s[0] * cs * cs + s[1] * sn * sn + 2 * s[3] * sn * cs;
    st[i] += s[0] * sn * sn + s[1] * cs * cs - 2 * s[3] * sn * cs;
  }
  res.settle = 0;
  for (int i = 0; i < nr; ++i) {
    const double r0 = pm.radii[i], r1 = pm.radii[i + 1];
    // Exact stresses averaged over the ring's area: the 1/r^2 term averages to
    // 2 ln(r1/r0) / (r1^2 - r0^2) (differs from 1/r_mid^2 by O(dtheta^2) ~ 0.1 %).
    const double inv_r2 = 2 * std::log(r1 / r0) / (r1 * r1 - r0 * r0);
    const double r_eq = 1.0 / std::sqrt(inv_r2);
    RadialRow row;
    row.r = r_eq;
    row.sr = sr[i] / n_theta;
    row.st = st[i] / n_theta;
    row.sr_ex = res.exact.sr(r_eq);
    row.st_ex = res.exact.st(r_eq);
    row.u = ring_u(i);
    row.u_ex = res.exact.u(r0);
    res.rings.push_back(row);
  }
  for (int i = 0; i < nr; ++i)
    res.settle = std::max(res.settle, std::abs(ring_u(i) - u_before[i]) / std::abs(res.exact.u(pm.radii[i]) + 1e-300));
  res.blocks = m.n_blocks();
  res.steps = sim.steps();
  res.dt = sim.dt();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("[lame 2D alpha=%g] blocks %zu, dt %.4g s, steps %lld, wall %.2f s, c_d %.4g 1/s, "
              "settle %.2e\n",
              alpha, res.blocks, res.dt, static_cast<long long>(res.steps), res.wall_s, c_d, res.settle);
  std::printf("  r/a     sr/sr_ex-1  st/st_ex-1  u(r_i)/u_ex-1  (u without springs: u/u_plain-1)\n");
  for (int i = 0; i < nr; ++i) {
    const auto& w = res.rings[i];
    std::printf("  %6.3f  %+8.3f%%  %+8.3f%%  %+8.3f%%  (%+8.3f%%)\n", w.r / a,
                100 * (w.sr / w.sr_ex - 1), 100 * (w.st / w.st_ex - 1), 100 * (w.u / w.u_ex - 1),
                100 * (w.u / res.plain.u(pm.radii[i]) - 1));
  }
  return res;
}

TEST(Lame2D, Explore) {
  const char* e = std::getenv("SWEEP");
  double a = 10, ba = 10, rw = 10, hw = 10; int nt = 24;
  if (e) std::sscanf(e, "%lf %lf %d %lf %lf", &a, &ba, &nt, &rw, &hw);
  run_lame_2d(a, ba, nt, rw, hw);
}

}  // namespace
}  // namespace cdem
