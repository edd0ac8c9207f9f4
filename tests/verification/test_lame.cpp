// Verification: the Lame problems, a pressurised cavity in an elastic body, solved to the static
// state by the explicit CDEM solver with mass-proportional damping (SPEC 1.4), blocks joined by
// unbreakable elastic springs (interface law 'elastic').
//
// 2D (plane strain): a circular hole of radius a in a disc of radius b = 10 a, pressure p on the
// hole wall, the outer circle fixed. A quarter of the disc with rollers on the two symmetry
// axes, meshed with a structured log-polar grid of quads: ring radii r_i = a q^i with
// q = exp(dtheta), so every cell is nearly square (radial width r (q - 1) ~ arc r dtheta).
// 3D: a spherical cavity of radius a in a ball of radius b = 3 a, pressure p on the cavity wall,
// the outer sphere fixed; an octant with rollers on the three symmetry planes, meshed with
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
// The finite outer radius is thus taken into account exactly (at the radii compared it changes
// u and the stresses by 5-20 % from the infinite-body values, which would not do here).
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
//     hydrostatic s I: eps = rho_n s <n n> = rho_n s I / 3  ->  1 / K' = 1 / K + rho_n
//     shear tau:       2 eps_12 = tau (4 rho_n / 15 + 2 rho_s / 5)
//                      ->  1 / G' = 1 / G + 4 rho_n / 15 + 2 rho_s / 5
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
#include <gmsh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
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

// Quasi-static schedule for the explicit solver: mass-proportional damping c_d, a linear
// pressure ramp over t_ramp, then a hold until t_end. omega_est is an estimate of the slowest
// mode (1/s). c_d = 1.4 omega_est gives a damping ratio c_d / (2 omega) of 0.7 at omega_est
// and 0.8 at the true fundamental of these models (~0.87 omega_est, measured); unlike
// c_d = 2 omega_est (critical at the estimate), it does not over-damp the fundamental when the
// estimate is high, which would slow its decay (an over-damped mode decays at only
// omega^2 / c_d). For a one-degree-of-freedom model of the slowest mode (omega = 0.85..1.3
// omega_est) a ramp of 6 / omega_est and a hold of 8 / omega_est leave a residual below
// 1.2e-3 of the static value; the runs also check that the state has settled.
struct QuasiStatic {
  double c_d, t_ramp, t_end;
};
QuasiStatic quasi_static(double omega_est, double ramp_w, double hold_w) {
  return {1.4 * omega_est, ramp_w / omega_est, (ramp_w + hold_w) / omega_est};
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
  double r = 0;                 // radius of the stress bin (m)
  double sr = 0, st = 0;        // mean block stresses (Pa): radial, hoop
  double sr_ex = 0, st_ex = 0;  // exact, averaged the same way
  double r_u = 0;               // radius of the displacement sample (m)
  double u = 0, u_ex = 0;       // mean vertex radial displacement (m), exact with springs
  double u_plain = 0;           // exact without the springs' compliance
};

struct Lame2DResult {
  std::vector<RadialRow> rings;  // one per ring of blocks (stresses) / ring of vertices (u)
  Lame exact, plain;             // effective-medium solution and the one without springs
  double settle = 0;             // max relative change of u over the last 10 % of the hold
  std::size_t blocks = 0;
  std::int64_t steps = 0;
  double dt = 0, wall_s = 0;
};

Lame2DResult run_lame_2d(double alpha, double b_over_a, int n_theta, double ramp_w, double hold_w) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double a = 0.1, b = b_over_a * a;
  PolarMesh pm = quarter_annulus(a, b, n_theta);

  const BlockMaterial probe = rock_with_damping(0);
  const double cp = probe.cp();
  // Quasi-static loading: slowest radial mode of a disc with a fixed rim, u = J1(k r),
  // J1(k b) = 0 -> omega_est = 3.8317 c_p / b (the hole and the springs lower it: a probe run,
  // undamped step load, found the dominant mode at 0.89 omega_est). See quasi_static().
  const QuasiStatic qs = quasi_static(3.8317 * cp / b, ramp_w, hold_w);
  const double c_d = qs.c_d, t_ramp = qs.t_ramp, t_end = qs.t_end;
  Case c;
  c.path = "test_lame 2D (in-code case)";
  c.title = "lame_2d";
  c.dt_safety = 0.5;
  c.materials = {rock_with_damping(c_d)};
  c.interfaces = {elastic_bond(alpha > 0 ? alpha : 10.0)};
  c.interface_mode = alpha > 0 ? InterfaceMode::Springs : InterfaceMode::Tied;  // 0: tied
  c.boundaries = {bc("hole", BoundaryType::Pressure, kP, {{0.0, 0.0}, {t_ramp, 1.0}}),
                  bc("outer", BoundaryType::Fixed), bc("xaxis", BoundaryType::Roller),
                  bc("yaxis", BoundaryType::Roller)};
  Simulation sim(build_model(pm.mesh, c.materials, c.interfaces, c.path), c);
  const Model& m = sim.model();

  // Vertex -> nodes (each mesh vertex was split into one node per block).
  const std::size_t nv = pm.mesh.vertices.size();
  std::vector<std::vector<std::int32_t>> vnodes(nv);
  for (std::size_t n = 0; n < m.n_nodes(); ++n)
    vnodes[m.node_vertex[n]].push_back(static_cast<std::int32_t>(n));
  const int nr = static_cast<int>(pm.radii.size()) - 1;
  auto ring_u = [&](int i) {  // mean radial displacement of the vertices of ring radius r_i
    double s = 0;
    int cnt = 0;
    for (int j = 0; j <= n_theta; ++j) {
      const auto v = j * (nr + 1) + i;
      const Vec3 X = pm.mesh.vertices[v];
      const Vec3 er = X / norm(X);
      double uv = 0;
      for (auto n : vnodes[v]) uv += dot(m.x[n] - m.X(n), er);
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
  // (tied, alpha = 0: no spring compliance, the plain medium)
  const double spring = alpha > 0 ? 1.0 / (alpha * kE) : 0.0;
  const double bulk2 = 1.0 / (1.0 / (2 * (lam + g)) + spring);  // 2 (lam' + G')
  const double g2 = 1.0 / (1.0 / (2 * g) + spring);             // 2 G'
  res.exact = {2, a, b, kP, 0.5 * bulk2 - 0.5 * g2, 0.5 * g2};
  res.plain = {2, a, b, kP, lam, g};

  // Stresses per ring of blocks; blocks are numbered ring-fastest (i + nr * j).
  std::vector<double> sr(nr, 0), st(nr, 0);
  for (std::size_t blk = 0; blk < m.n_blocks(); ++blk) {
    const auto e = m.block_elem_tag[blk] - 1;
    const int i = static_cast<int>(e % nr);
    Vec3 cen{};
    for (auto n = m.block_first_node[blk]; n < m.block_first_node[blk + 1]; ++n) cen += m.X(n);
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
    row.r_u = r0;
    row.u = ring_u(i);
    row.u_ex = res.exact.u(r0);
    row.u_plain = res.plain.u(r0);
    res.rings.push_back(row);
  }
  // Settling: the largest change of a ring's displacement over the last 10 % of the hold,
  // relative to the wall displacement.
  for (int i = 0; i <= nr; ++i)
    res.settle = std::max(res.settle, std::abs(ring_u(i) - u_before[i]) / res.exact.u(a));
  res.blocks = m.n_blocks();
  res.steps = sim.steps();
  res.dt = sim.dt();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf(
      "[lame 2D alpha=%g] blocks %zu, dt %.4g s, steps %lld, wall %.2f s, c_d %.4g 1/s, "
      "settle %.2e\n",
      alpha, res.blocks, res.dt, static_cast<long long>(res.steps), res.wall_s, c_d, res.settle);
  std::printf(
      "  stresses: error / (p a^2 / r^2); u: u / u_ex - 1 and (u / u_plain - 1)\n"
      "  r/a     sr err    st err    | r_u/a   u err     (no springs)\n");
  for (int i = 0; i < nr; ++i) {
    const auto& w = res.rings[i];
    const double scale = kP * (a / w.r) * (a / w.r);
    std::printf("  %6.3f  %+7.3f%%  %+7.3f%%  | %6.3f  %+7.3f%%  (%+7.3f%%)\n", w.r / a,
                100 * (w.sr - w.sr_ex) / scale, 100 * (w.st - w.st_ex) / scale, w.r_u / a,
                100 * (w.u / w.u_ex - 1), 100 * (w.u / w.u_plain - 1));
  }
  return res;
}

// ---------------------------------------------------------------------------------------------
// 3D: octant of a ball with a spherical cavity, Gmsh tetrahedra
// ---------------------------------------------------------------------------------------------

// Octant 0 <= x, y, z of the shell a <= r <= b, meshed by Gmsh with the element size
// beta * r (clipped below at h_min): regions "rock"; face sets "cavity" (r = a), "outer"
// (r = b), "sym_x", "sym_y", "sym_z" (the planes x = 0, y = 0, z = 0).
Mesh sphere_octant_mesh(double a, double b, double beta, double h_min) {
  GmshSession session("test_lame sphere octant");
  try {
    namespace occ = gmsh::model::occ;
    namespace field = gmsh::model::mesh::field;
    gmsh::model::add("lame_sphere_octant");
    gmsh::vectorpair shell, body;
    std::vector<gmsh::vectorpair> map;
    occ::intersect({{3, occ::addSphere(0, 0, 0, b)}}, {{3, occ::addBox(0, 0, 0, b, b, b)}}, shell,
                   map);
    occ::cut(shell, {{3, occ::addSphere(0, 0, 0, a)}}, body, map);
    occ::synchronize();
    const int f = field::add("MathEval");
    char expr[128];
    std::snprintf(expr, sizeof expr, "Max(%.17g, %.17g * Sqrt(x^2 + y^2 + z^2))", h_min, beta);
    field::setString(f, "F", expr);
    field::setAsBackgroundMesh(f);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    gmsh::option::setNumber("Mesh.Optimize", 1);
    gmsh::model::mesh::generate(3);
    session.check_log();
    std::vector<int> vols;
    for (const auto& dt : body) vols.push_back(dt.second);
    gmsh::model::addPhysicalGroup(3, vols, 1);
    gmsh::model::setPhysicalName(3, 1, "rock");
    // Classify the boundary surfaces by their bounding boxes.
    const double tol = 1e-6 * b;
    std::vector<int> cavity, outer, sx, sy, sz;
    gmsh::vectorpair surfaces;
    gmsh::model::getEntities(surfaces, 2);
    for (const auto& [d, tag] : surfaces) {
      double x0, y0, z0, x1, y1, z1;
      gmsh::model::getBoundingBox(d, tag, x0, y0, z0, x1, y1, z1);
      if (x1 - x0 < tol)
        sx.push_back(tag);
      else if (y1 - y0 < tol)
        sy.push_back(tag);
      else if (z1 - z0 < tol)
        sz.push_back(tag);
      else if (std::max({x1, y1, z1}) < a + 1e-3 * a)
        cavity.push_back(tag);
      else
        outer.push_back(tag);
    }
    int g = 1;
    for (const auto& [name, tags] : std::vector<std::pair<std::string, std::vector<int>>>{
             {"cavity", cavity}, {"outer", outer}, {"sym_x", sx}, {"sym_y", sy}, {"sym_z", sz}}) {
      gmsh::model::addPhysicalGroup(2, tags, ++g);
      gmsh::model::setPhysicalName(2, g, name);
    }
    return detail::extract_gmsh_model("test_lame sphere octant");
  } catch (...) {
    session.rethrow_as_mesh_error();
  }
}

struct Lame3DResult {
  std::vector<RadialRow> bins;
  std::vector<double> edges;  // bin edges in r / a
  Lame exact, plain;          // Reuss effective medium, and without springs
  double rho_n = 0;           // 1/Pa
  double settle = 0;
  std::size_t blocks = 0;
  std::int64_t steps = 0;
  double dt = 0, wall_s = 0, mesh_s = 0;
};

// 4-point (degree 2) rule on a tetrahedron: the exact stress averaged over a block.
template <class F>
Sym6 tet_average(const Vec3* p, F stress_at) {
  constexpr double al = 0.5854101966249685, be = 0.1381966011250105;
  Sym6 s{};
  for (int q = 0; q < 4; ++q) {
    Vec3 x{};
    for (int k = 0; k < 4; ++k) x += (k == q ? al : be) * p[k];
    const Sym6 v = stress_at(x);
    for (int c = 0; c < 6; ++c) s[c] += 0.25 * v[c];
  }
  return s;
}

// Spherical components of a stress at the direction er: (sigma_rr, mean hoop stress).
std::pair<double, double> spherical(const Sym6& s, Vec3 er) {
  const Vec3 t{s[0] * er.x + s[3] * er.y + s[5] * er.z, s[3] * er.x + s[1] * er.y + s[4] * er.z,
               s[5] * er.x + s[4] * er.y + s[2] * er.z};
  const double srr = dot(t, er);
  return {srr, 0.5 * (s[0] + s[1] + s[2] - srr)};
}

Lame3DResult run_lame_3d(double alpha, double b_over_a, double beta, double ramp_w, double hold_w) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double a = 0.1, b = b_over_a * a;
  Mesh mesh = sphere_octant_mesh(a, b, beta, 0.0);
  Lame3DResult res;
  res.mesh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  const BlockMaterial probe = rock_with_damping(0);
  const double cp = probe.cp();
  // Slowest radial mode of a ball with a fixed surface: u = j1(k r), j1(k b) = 0 ->
  // omega_est = 4.4934 c_p / b (a probe run found the cavity model's dominant mode at
  // 0.87 omega_est). See quasi_static().
  const QuasiStatic qs = quasi_static(4.4934 * cp / b, ramp_w, hold_w);
  const double c_d = qs.c_d, t_ramp = qs.t_ramp, t_end = qs.t_end;
  Case c;
  c.path = "test_lame 3D (in-code case)";
  c.title = "lame_3d";
  c.dt_safety = 0.5;
  c.materials = {rock_with_damping(c_d)};
  c.interfaces = {elastic_bond(alpha > 0 ? alpha : 10.0)};
  c.interface_mode = alpha > 0 ? InterfaceMode::Springs : InterfaceMode::Tied;  // 0: tied
  c.boundaries = {bc("cavity", BoundaryType::Pressure, kP, {{0.0, 0.0}, {t_ramp, 1.0}}),
                  bc("outer", BoundaryType::Fixed), bc("sym_x", BoundaryType::Roller),
                  bc("sym_y", BoundaryType::Roller), bc("sym_z", BoundaryType::Roller)};
  Simulation sim(build_model(mesh, c.materials, c.interfaces, c.path), c);
  const Model& m = sim.model();

  // Effective medium (header comment): rho_n from the model's own interfaces.
  double vol = 0, sum = 0;
  for (std::size_t k = 0; k < m.n_blocks(); ++k) vol += m.block_volume0[k];
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    const auto s0 = i * m.springs_per_iface;
    // the face area: the interface's np spring points share it (A_c = A / np)
    sum += m.springs_per_iface * m.sp_area[s0] / (m.sp_kn[s0] / m.sp_area[s0]);
  }
  res.rho_n = alpha > 0 ? sum / vol : 0.0;  // tied: no spring compliance
  const double lam = probe.lambda(), g = probe.shear(), kb = probe.bulk();
  const double rho_s = res.rho_n * kE / g;
  const double k_eff = 1.0 / (1.0 / kb + res.rho_n);
  const double g_eff = 1.0 / (1.0 / g + 4 * res.rho_n / 15 + 2 * rho_s / 5);
  res.exact = {3, a, b, kP, k_eff - 2 * g_eff / 3, g_eff};
  res.plain = {3, a, b, kP, lam, g};

  std::vector<std::vector<std::int32_t>> vnodes(mesh.vertices.size());
  for (std::size_t n = 0; n < m.n_nodes(); ++n)
    vnodes[m.node_vertex[n]].push_back(static_cast<std::int32_t>(n));
  auto vertex_ur = [&](std::size_t v) {
    const Vec3 X = mesh.vertices[v];
    const Vec3 er = X / norm(X);
    double uv = 0;
    for (auto n : vnodes[v]) uv += dot(m.x[n] - m.X(n), er);
    return uv / vnodes[v].size();
  };
  std::vector<double> u_before;
  bool saved = false;
  while (sim.time() < t_end) {
    if (!saved && sim.time() >= t_end - 0.1 * (t_end - t_ramp)) {
      for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
        u_before.push_back(vnodes[v].empty() ? 0 : vertex_ur(v));
      saved = true;
    }
    sim.step();
  }
  const double u_wall = res.exact.u(a);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    if (!vnodes[v].empty())
      res.settle = std::max(res.settle, std::abs(vertex_ur(v) - u_before[v]) / u_wall);

  // Radial bins (in r / a), geometric.
  std::vector<double> edges{1.0, 1.2, 1.4, 1.7, 2.0, 2.4, 2.8, 3.5, 4.0, 4.5, 5.0};
  while (edges.back() > b_over_a + 1e-9) edges.pop_back();
  const std::size_t nb = edges.size() - 1;
  res.edges = edges;
  std::vector<double> s_r(nb, 0), s_t(nb, 0), e_r(nb, 0), e_t(nb, 0), u(nb, 0), ue(nb, 0),
      up(nb, 0), rr(nb, 0);
  std::vector<int> nblk(nb, 0), nvtx(nb, 0);
  auto bin_of = [&](double r) {
    for (std::size_t k = 0; k < nb; ++k)
      if (r >= edges[k] * a && r < edges[k + 1] * a) return static_cast<int>(k);
    return -1;
  };
  const Lame ex = res.exact;
  auto exact_stress = [&](Vec3 x) {
    const double r = norm(x);
    const Vec3 n = x / r;
    const double sr = ex.sr(r), st = ex.st(r);
    // sigma = st I + (sr - st) n n
    return Sym6{st + (sr - st) * n.x * n.x, st + (sr - st) * n.y * n.y, st + (sr - st) * n.z * n.z,
                (sr - st) * n.x * n.y,      (sr - st) * n.y * n.z,      (sr - st) * n.x * n.z};
  };
  for (std::size_t k = 0; k < m.n_blocks(); ++k) {
    Vec3 p[4], cen{};
    for (int q = 0; q < 4; ++q) {
      p[q] = m.X(m.block_first_node[k] + q);
      cen += 0.25 * p[q];
    }
    const int bi = bin_of(norm(cen));
    if (bi < 0) continue;
    const Vec3 er = cen / norm(cen);
    const auto [sr, st] = spherical(m.stress[k], er);
    const auto [xr, xt] = spherical(tet_average(p, exact_stress), er);
    s_r[bi] += sr;
    s_t[bi] += st;
    e_r[bi] += xr;
    e_t[bi] += xt;
    rr[bi] += norm(cen);
    ++nblk[bi];
  }
  std::vector<double> ru(nb, 0);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (vnodes[v].empty()) continue;
    const double r = norm(mesh.vertices[v]);
    const int bi = bin_of(r);
    if (bi < 0) continue;
    ru[bi] += r;
    u[bi] += vertex_ur(v);
    ue[bi] += ex.u(r);
    up[bi] += res.plain.u(r);
    ++nvtx[bi];
  }
  for (std::size_t k = 0; k < nb; ++k) {
    RadialRow row;
    row.r = nblk[k] ? rr[k] / nblk[k] : 0;
    row.sr = nblk[k] ? s_r[k] / nblk[k] : 0;
    row.st = nblk[k] ? s_t[k] / nblk[k] : 0;
    row.sr_ex = nblk[k] ? e_r[k] / nblk[k] : 0;
    row.st_ex = nblk[k] ? e_t[k] / nblk[k] : 0;
    row.r_u = nvtx[k] ? ru[k] / nvtx[k] : 0;
    row.u = nvtx[k] ? u[k] / nvtx[k] : 0;
    row.u_ex = nvtx[k] ? ue[k] / nvtx[k] : 0;
    row.u_plain = nvtx[k] ? up[k] / nvtx[k] : 0;
    res.bins.push_back(row);
  }
  res.blocks = m.n_blocks();
  res.steps = sim.steps();
  res.dt = sim.dt();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf(
      "[lame 3D alpha=%g] tets %zu, dt %.4g s (%s), steps %lld, mesh %.2f s, total %.2f s, "
      "rho_n E = %.4f, G/G' = %.4f, K/K' = %.4f, settle %.2e\n",
      alpha, res.blocks, res.dt, sim.stable().limit.c_str(), static_cast<long long>(res.steps),
      res.mesh_s, res.wall_s, res.rho_n * kE, g / g_eff, kb / k_eff, res.settle);
  std::printf(
      "  stresses: error / (p a^3 / r^3) (hoop: / (p a^3 / (2 r^3))); u: u / u_ex - 1, "
      "(u / u_plain - 1)\n  bin r/a    blocks  sr err    st err    | u err     (no springs)\n");
  for (std::size_t k = 0; k < nb; ++k) {
    const auto& w = res.bins[k];
    const double scale = kP * std::pow(a / w.r, 3);
    std::printf("  %4.2f-%4.2f %5d  %+7.3f%%  %+7.3f%%  | %+7.3f%%  (%+7.3f%%)\n", edges[k],
                edges[k + 1], nblk[k], 100 * (w.sr - w.sr_ex) / scale,
                100 * (w.st - w.st_ex) / (0.5 * scale), 100 * (w.u / w.u_ex - 1),
                100 * (w.u / w.u_plain - 1));
  }
  return res;
}

// ---------------------------------------------------------------------------------------------
// The checks. CTest starts one process per test, so each test runs the models it needs (cached
// within a process); the tables are printed for docs/verification_waves_lame.md.
// ---------------------------------------------------------------------------------------------

// 2D: alpha = 10 (the default interface stiffness), where the springs soften the body by 8 %:
// the displacement check below fails if their compliance is not accounted for.
// 24 cells over 90 degrees (3.75 degrees; the cells at the wall are 6.5 mm for a = 0.1 m),
// b = 10 a (35 rings): 840 blocks.
const Lame2DResult& lame_2d() {
  static const Lame2DResult r = run_lame_2d(10.0, 10.0, 24, 6.0, 8.0);
  return r;
}

// 3D: b = 3 a, element size 0.12 r (about 5400 tets), the finest mesh that keeps the test
// within its time budget; alpha = 100 (springs soften by ~3 %) and alpha = 10 (~30 %).
const Lame3DResult& lame_3d(double alpha) {
  if (alpha == 0.0) {
    static const Lame3DResult r0 = run_lame_3d(0.0, 3.0, 0.12, 6.0, 8.0);
    return r0;
  }
  if (alpha == 100.0) {
    static const Lame3DResult r100 = run_lame_3d(100.0, 3.0, 0.12, 6.0, 8.0);
    return r100;
  }
  static const Lame3DResult r10 = run_lame_3d(10.0, 3.0, 0.12, 6.0, 8.0);
  return r10;
}

// The radii compared: a few cells away from the wall (the first rings carry the O(h) wall
// error of the discretisation), up to half the outer radius.
constexpr double kRadii2D[] = {1.5, 2.0, 3.0, 5.0};  // r / a

const RadialRow& ring_near(const Lame2DResult& res, double r) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < res.rings.size(); ++i)
    if (std::abs(res.rings[i].r - r) < std::abs(res.rings[best].r - r)) best = i;
  return res.rings[best];
}

// Static state: the largest change of a ring's (2D) or vertex's (3D) radial displacement over
// the last 10 % of the hold, relative to the wall displacement. The quasi-static schedule
// predicts a residual ~1e-3 (quasi_static()); below 2e-3 (measured 4e-4 .. 5e-4) it is 5x below
// the accuracy tolerances, so the comparisons see the static state.
constexpr double kSettleTol = 2e-3;

// 2D checks.
// - Stresses against the thick-cylinder solution, error relative to the local magnitude
//   p a^2 / r^2 (the hoop stress crosses zero at r = b sqrt(G' / (lambda' + G')) ~ 0.7 b, where
//   a relative error is meaningless). Measured errors at these radii: <= 0.29 % (sigma_r),
//   <= 0.25 % (sigma_theta), decreasing with the cell size (DISABLED_MeshAndAlphaStudy).
//   Tolerance 1 %: the brief's "few %" tightened to ~3x the measured discretisation error.
// - Radial displacement against the thick-cylinder solution of the effective medium (blocks +
//   springs, header comment). Measured errors at these radii: -0.34 % to -0.61 %, decreasing
//   with the cell size; with alpha = 1000 (springs negligible) the same mesh gives about
//   -0.15 % to -0.2 %. Tolerance 1.5 %: 2.5x the measured error, and 1/5 of the 7.6 % by which
//   the solution without the springs' compliance is off (also checked: that solution must miss
//   by more than the tolerance, so the check does see alpha).
TEST(Lame2D, PressurisedHoleMatchesThickCylinder) {
  const auto& res = lame_2d();
  const double a = res.exact.a;
  EXPECT_LT(res.settle, kSettleTol);
  for (double ra : kRadii2D) {
    const auto& w = ring_near(res, ra * a);
    const double scale = kP * (a / w.r) * (a / w.r);
    EXPECT_NEAR((w.sr - w.sr_ex) / scale, 0.0, 0.01) << "sigma_r at r = " << w.r / a << " a";
    EXPECT_NEAR((w.st - w.st_ex) / scale, 0.0, 0.01) << "sigma_theta at r = " << w.r / a << " a";
    EXPECT_NEAR(w.u / w.u_ex, 1.0, 0.015) << "u at r = " << w.r_u / a << " a";
    EXPECT_GT(std::abs(w.u / w.u_plain - 1.0), 0.015) << "u at r = " << w.r_u / a << " a";
  }
}

// 3D bins compared: 1.2 a to 2.4 a (the first bin holds the wall layer, the last one the coarse
// cells next to the fixed outer sphere at 3 a).
template <class F>
void for_bins_3d(const Lame3DResult& res, F check) {
  int n = 0;
  for (std::size_t k = 0; k < res.bins.size(); ++k)
    if (res.edges[k] >= 1.2 - 1e-9 && res.edges[k + 1] <= 2.4 + 1e-9) {
      check(res.bins[k], res.edges[k], res.edges[k + 1]);
      ++n;
    }
  EXPECT_EQ(n, 4);
}

// 3D checks (one test: the two runs take most of the verification budget).
// - Stresses against the thick-sphere solution, errors relative to p a^3 / r^3 (radial) and
//   p a^3 / (2 r^3) (hoop). Constant-strain tets of size 0.12 r: measured errors +1.9..+2.7 %
//   (sigma_r) and -1.1..+0.4 % (sigma_t)
//   (discretisation, shrinking with the element size: 3.3-4.3 % at 0.15 r, 1.1-2.2 % at
//   0.10 r; DISABLED_MeshAndAlphaStudy); the springs hardly matter (alpha = 1000 gives the
//   same errors within 0.3 %). Tolerance 4 % ("a few %" of the brief): 1.5x the measured
//   error of this coarse mesh.
// - Radial displacement (alpha = 100) against the thick-sphere solution of the effective
//   medium with the Reuss-type spring compliance (an upper bound: the true softening is 80-90 %
//   of it here). Measured: -1.9..-2.0 %, the tets' stiffness error (-1.4..-1.6 % with
//   alpha = 1000) plus the bound's gap (about -0.4 %). Tolerance 4 % as for the stresses. At alpha
//   = 100 the springs' effect (3.5 %) is below this mesh's accuracy: the alpha dependence is
//   checked by the ratio.
// - Softening by the springs: u(alpha = 10) / u(alpha = 100) on the same mesh, where the
//   discretisation error cancels; the Reuss estimate predicts 1.306 (no springs: 1.0). The
//   estimate is an upper bound of the compliance (the uniform-stress field is statically
//   admissible: complementary energy), exact only for compatible (structured) blocks.
//   Tolerance 5 % around it (measured -0.2 .. -2.2 %), which still rejects a spring effect
//   smaller than 5/6 of the predicted one.
// - Model size guard (the brief: within ~20 s on 2 threads): block and step counts.
TEST(Lame3D, SphericalCavityMatchesThickSphere) {
  const auto& res = lame_3d(100.0);
  const auto& r10 = lame_3d(10.0);
  const double a = res.exact.a;
  EXPECT_LT(res.settle, kSettleTol);
  EXPECT_LT(r10.settle, kSettleTol);
  ASSERT_EQ(r10.bins.size(), res.bins.size());
  std::size_t k = 0;
  for_bins_3d(res, [&](const RadialRow& w, double lo, double hi) {
    while (res.edges[k] < lo - 1e-9) ++k;
    const double scale = kP * std::pow(a / w.r, 3);
    EXPECT_NEAR((w.sr - w.sr_ex) / scale, 0.0, 0.04) << "sigma_r in " << lo << "-" << hi << " a";
    EXPECT_NEAR((w.st - w.st_ex) / (0.5 * scale), 0.0, 0.04)
        << "sigma_t in " << lo << "-" << hi << " a";
    EXPECT_NEAR(w.u / w.u_ex, 1.0, 0.04) << "u in " << lo << "-" << hi << " a";
    const double measured = r10.bins[k].u / w.u;
    const double predicted = r10.bins[k].u_ex / w.u_ex;
    std::printf("[lame 3D] u(alpha=10)/u(alpha=100) in %.1f-%.1f a: measured %.4f, Reuss %.4f\n",
                lo, hi, measured, predicted);
    EXPECT_NEAR(measured / predicted, 1.0, 0.05) << "u ratio in " << lo << "-" << hi << " a";
  });
  EXPECT_LT(res.blocks, 8000u);
  EXPECT_LT(res.steps, 10000);
}

// Tied interfaces (the default mode): the rock is the conforming tet mesh, no spring compliance,
// on the mesh where alpha = 10 springs soften it by ~30 %.
// - Radial displacement against the plain thick-sphere solution, within 3 % away from the wall
//   (1.2 a to 2.4 a): the constant-strain tets' own stiffness error on this mesh is -1.4 to
//   -1.6 % (measured with alpha = 1000 springs, DISABLED_MeshAndAlphaStudy); 3 % is twice it.
// - Stresses as above (4 %).
TEST(Lame3D, TiedSphericalCavityMatchesThickSphere) {
  const auto& res = lame_3d(0.0);
  const double a = res.exact.a;
  EXPECT_LT(res.settle, kSettleTol);
  for_bins_3d(res, [&](const RadialRow& w, double lo, double hi) {
    const double scale = kP * std::pow(a / w.r, 3);
    EXPECT_NEAR((w.sr - w.sr_ex) / scale, 0.0, 0.04) << "sigma_r in " << lo << "-" << hi << " a";
    EXPECT_NEAR((w.st - w.st_ex) / (0.5 * scale), 0.0, 0.04)
        << "sigma_t in " << lo << "-" << hi << " a";
    EXPECT_NEAR(w.u / w.u_ex, 1.0, 0.03) << "u in " << lo << "-" << hi << " a";
    std::printf("[lame 3D tied] %.1f-%.1f a: u / u_exact %.4f, sigma_r error %+.2f %%, sigma_t "
                "error %+.2f %%\n",
                lo, hi, w.u / w.u_ex, 100 * (w.sr - w.sr_ex) / scale,
                100 * (w.st - w.st_ex) / (0.5 * scale));
  });
}

// Tied 2D: the quad annulus of the test above with tied interfaces: the plain thick-cylinder
// solution. Stresses 1 % and displacement 1.5 % as above (with alpha = 1000 springs the same
// mesh gives -0.15 .. -0.2 % on u).
TEST(Lame2D, TiedPressurisedHoleMatchesThickCylinder) {
  static const Lame2DResult res = run_lame_2d(0.0, 10.0, 24, 6.0, 8.0);
  const double a = res.exact.a;
  EXPECT_LT(res.settle, kSettleTol);
  for (double ra : kRadii2D) {
    const auto& w = ring_near(res, ra * a);
    const double scale = kP * (a / w.r) * (a / w.r);
    EXPECT_NEAR((w.sr - w.sr_ex) / scale, 0.0, 0.01) << "sigma_r at r = " << w.r / a << " a";
    EXPECT_NEAR((w.st - w.st_ex) / scale, 0.0, 0.01) << "sigma_theta at r = " << w.r / a << " a";
    EXPECT_NEAR(w.u / w.u_ex, 1.0, 0.015) << "u at r = " << w.r_u / a << " a";
    std::printf("[lame 2D tied] r = %.1f a: u / u_exact %.4f\n", w.r_u / a, w.u / w.u_ex);
  }
}

// Studies behind the tolerances (docs/verification_waves_lame.md), not run by default (minutes
// of CPU): run with --gtest_also_run_disabled_tests --gtest_filter='*Study*'. They check that
// the errors are discretisation errors (they shrink with the element size) and that with
// nearly rigid springs (alpha = 1000) the solution without springs is recovered.
double max_u_error_2d(const Lame2DResult& res, bool plain) {
  double e = 0;
  for (double ra : kRadii2D) {
    const auto& w = ring_near(res, ra * res.exact.a);
    e = std::max(e, std::abs(w.u / (plain ? w.u_plain : w.u_ex) - 1.0));
  }
  return e;
}

TEST(Lame2D, DISABLED_MeshAndAlphaStudy) {
  const auto& base = lame_2d();
  const Lame2DResult fine = run_lame_2d(10.0, 10.0, 48, 6.0, 8.0);
  const Lame2DResult stiff = run_lame_2d(1000.0, 10.0, 24, 6.0, 8.0);
  EXPECT_LT(max_u_error_2d(fine, false), 0.7 * max_u_error_2d(base, false));
  // alpha = 1000: the springs add 0.08 % of compliance; the solution without springs holds
  // to the discretisation error of the base mesh.
  EXPECT_LT(max_u_error_2d(stiff, true), max_u_error_2d(base, false));
}

double max_stress_error_3d(const Lame3DResult& res) {
  double e = 0;
  for_bins_3d(res, [&](const RadialRow& w, double, double) {
    const double scale = kP * std::pow(res.exact.a / w.r, 3);
    e = std::max({e, std::abs(w.sr - w.sr_ex) / scale, std::abs(w.st - w.st_ex) / (0.5 * scale)});
  });
  return e;
}

TEST(Lame3D, DISABLED_MeshAndAlphaStudy) {
  const auto& base = lame_3d(100.0);
  const Lame3DResult coarse = run_lame_3d(100.0, 3.0, 0.15, 6.0, 8.0);
  const Lame3DResult fine = run_lame_3d(100.0, 3.0, 0.10, 6.0, 8.0);
  const Lame3DResult stiff = run_lame_3d(1000.0, 3.0, 0.12, 6.0, 8.0);
  EXPECT_LT(max_stress_error_3d(fine), max_stress_error_3d(base));
  EXPECT_LT(max_stress_error_3d(base), max_stress_error_3d(coarse));
  // The springs do not change the stresses: alpha = 1000 and 100 agree to well below the
  // discretisation error.
  EXPECT_LT(std::abs(max_stress_error_3d(stiff) - max_stress_error_3d(base)), 0.01);
}

}  // namespace
}  // namespace cdem
