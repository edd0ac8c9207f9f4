// Verification of the gas model against two static elastic solutions (issue 13; explosive/gas.hpp,
// docs/theory.md "Bar charges: the gas", numbers in docs/verification_gas.md):
//  - quasi-static cavity: a solid charge with gas = "cavity" in a cylindrical hole of a plane-
//    strain elastic disc settles where the explosive's adiabat P(V) meets the thick-cylinder
//    compliance of the hole;
//  - pressurised crack (Sneddon): pre-broken interfaces along a straight crack, their faces pushed
//    apart by the gas-in-cracks loads of update_gas (the "cracks" model's crack face pressure) at
//    a fixed pressure; the opening against Sneddon's ellipse.
// Both run in tied interface mode (the intact rock is the conforming continuum: no spring
// compliance to correct for), with mass-proportional damping to reach the static state.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "cdem/explosive/charges.hpp"
#include "cdem/io/case.hpp"
#include "cdem/explosive/eos.hpp"
#include "cdem/explosive/gas.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/charge_builders.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;
using namespace test_charges;

constexpr double kE = 10e9, kNu = 0.25, kRho = 2500.0;  // SPEC 5.1 rock (lambda = G = 4 GPa)

BoundaryCondition boundary(const std::string& faces, BoundaryType type) {
  BoundaryCondition b;
  b.faces = faces;
  b.type = type;
  b.table.points = {{0.0, 1.0}};
  return b;
}

// Pressure -> relative volume on the isentrope (P decreasing in v): bisection on log v.
double volume_at_pressure(const Eos& eos, double p) {
  double lo = std::log(1e-3), hi = std::log(1e15);
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (eos_pressure(eos, std::exp(mid)) > p ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

// ---------------------------------------------------------------------------------------------
// 1. Quasi-static cavity
// ---------------------------------------------------------------------------------------------
//
// A quarter of a disc (rollers on the two symmetry axes), rock between the hole radius a and the
// outer radius b = 10 a (outer circle fixed), on the structured log-polar quads of test_lame.cpp
// (24 cells over 90 degrees, nearly square cells; the builder there is local to that file, so it
// is repeated here), and the hole filled with explosive blocks: a fan of 24 triangles from the
// centre to the wall's segments. The explosive blocks of a solid charge carry pressure only (no
// stiffness), so the rock alone resists; with gas = "cavity" the deck is one gas body of mass
// rho_w V0 (fully burnt) filling the explosive blocks' total area V, at P = EOS(V / V0).
//
// The fixed point: P = EOS(1 + eps) with eps = dV / V0 the hole's area change under a wall
// pressure P. Thick cylinder, plane strain, u(b) = 0, sigma_r(a) = -P (test_lame.cpp):
//   u(a) = A a + B / a,  B = P / (2 G / a^2 + 2 (lambda + G) / b^2),  A = -B / b^2,
//   eps = (1 + u(a) / a)^2 - 1          (infinite medium: eps = P / G = 2 P (1 + nu) / E).
// The fixed outer circle makes the hole 3 % stiffer than in the infinite medium at b = 10 a
// (eps_inf / eps_fix = 1.030, printed): the exact thick-cylinder compliance is used.
//
// Explosive: Landau with rho_w = 1000 kg/m^3, D = 300 m/s (P0 = rho D^2 / 8 = 11.25 MPa =
// 1.1e-3 E), Q = 12 kJ/kg (Q rho / P0 = 1.07, about the emulsion's 0.99; the stage change is at
// v = 2, far from the small strains here), gamma 3 / 1.33. At equilibrium eps ~ 2.8e-3 (small
// strain: linear elasticity and the co-rotational blocks agree to ~1e-3 of eps) and the gas has
// lost 3 eps = 0.8 % of P0. The pressure itself is therefore close to P0 whatever the rock does;
// what discriminates is eps and the pressure drop P0 - P (its relative error is eps's), both
// checked.
//
// Loading: the charge burns from the centre at D (all blocks within a / D = 0.33 ms, each over
// L_c / D); mass-proportional damping c_d = 1.4 omega_est, omega_est = 3.8317 c_p / b (the
// disc's slowest radial mode with a fixed rim; test_lame.cpp's quasi_static() reasoning:
// damping ratio 0.7-0.8 on the fundamental, and every underdamped mode decays as
// exp(-c_d t / 2)), held until 16 / omega_est after the burn: the residual of a damped
// oscillator at that time is ~1e-5 of the static value; the run checks that P and eps have
// settled (change over the last 10 % of the run).

struct CavityResult {
  double p = 0, eps = 0;        // measured: gas pressure (Pa), cavity area change / V0
  double eps_wall = 0;          // the hole's area change from the rock's wall nodes
  double p_fix = 0, eps_fix = 0, p0 = 0;  // fixed point and the adiabat's P(1)
  double eps_inf = 0;           // the infinite-medium compliance at p_fix: p_fix / G
  double settle = 0;            // relative change of eps over the last 10 % of the run
  double vented = 0;
  std::size_t blocks = 0;
  std::int64_t steps = 0;
  double wall_s = 0;
};

CavityResult run_cavity(int n_theta) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double a = 0.1, b = 10 * a;
  // Rock: log-polar rings r_i = a q^i (as test_lame.cpp's quarter_annulus), plus a centre vertex.
  const double dth = 0.5 * kPi / n_theta;
  const int nr = static_cast<int>(std::lround(std::log(b / a) / dth));
  const double q = std::pow(b / a, 1.0 / nr);
  Mesh mesh;
  mesh.dim = 2;
  mesh.region_names = {"rock", "charge"};
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nr + 1) + i); };
  for (int j = 0; j <= n_theta; ++j) {
    const double c = j == n_theta ? 0.0 : std::cos(j * dth), s = j == 0 ? 0.0 : std::sin(j * dth);
    for (int i = 0; i <= nr; ++i) {
      const double r = i == nr ? b : a * std::pow(q, i);
      mesh.vertices.push_back({r * c, r * s, 0.0});
    }
  }
  const auto centre = static_cast<std::int32_t>(mesh.vertices.size());
  mesh.vertices.push_back({0.0, 0.0, 0.0});
  auto add = [&](ElemType t, std::array<std::int32_t, 4> v, std::int32_t region) {
    mesh.elem_type.push_back(t);
    mesh.elem_vertices.push_back(v);
    mesh.elem_region.push_back(region);
    mesh.elem_tag.push_back(static_cast<std::int64_t>(mesh.elem_tag.size() + 1));
  };
  for (int j = 0; j < n_theta; ++j)
    for (int i = 0; i < nr; ++i)
      add(ElemType::Quad4, {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)}, 0);
  for (int j = 0; j < n_theta; ++j) add(ElemType::Tri3, {centre, vid(0, j), vid(0, j + 1), -1}, 1);
  FaceSet outer{"outer", {}}, xaxis{"xaxis", {}}, yaxis{"yaxis", {}};
  for (int j = 0; j < n_theta; ++j) outer.facets.push_back({{vid(nr, j), vid(nr, j + 1), -1}});
  for (int i = 0; i < nr; ++i) {
    xaxis.facets.push_back({{vid(i, 0), vid(i + 1, 0), -1}});
    yaxis.facets.push_back({{vid(i, n_theta), vid(i + 1, n_theta), -1}});
  }
  xaxis.facets.push_back({{centre, vid(0, 0), -1}});
  yaxis.facets.push_back({{vid(0, n_theta), centre, -1}});
  mesh.face_sets = {outer, xaxis, yaxis};
  check_mesh(mesh, "test_gas_elastic cavity");

  const Eos eos = LandauEos::make(1000.0, 300.0, 12e3, 3.0, 1.33, "test_gas_elastic weak");
  const double cp = rock().cp();
  const double omega = 3.8317 * cp / b, c_d = 1.4 * omega;
  BlockMaterial stone = rock(kE, kNu, kRho);
  stone.damping = c_d;
  BlockMaterial ex;
  ex.name = "weak_charge";
  ex.regions = {"charge"};
  ex.explosive = "weak";
  ex.density = 1000;
  ex.youngs = 1e9;  // unused (an explosive block has no stiffness), as load_case's default
  ex.poisson = 0.25;
  ex.damping = c_d;
  const std::vector<BlockMaterial> mats{stone, ex};
  const std::vector<InterfaceMaterial> ifs{interface_of(InterfaceLaw::Elastic)};
  Case c = make_case(mats, ifs);
  c.path = "test_gas_elastic cavity (in-code case)";
  c.interface_mode = InterfaceMode::Tied;
  c.explosives = {{"weak", eos}};
  // A deck perpendicular to the plane is not expressible in 2D (holes lie in the plane): a deck
  // of length 1e-3 a at the centre with diameter 2 a holds every explosive block (centroids
  // within a + L_c / 2 of its axis) and initiates at the centre.
  HoleDef h = make_hole("cavity", {0.0, 1e-3 * a, 0.0}, {0.0, 0.0, 0.0}, 2 * a,
                        {{1e-3 * a, 0.0, false, 0.0, "weak"}}, ChargeModel::Solid);
  h.gas = GasModel::Cavity;
  c.holes = {h};
  c.boundaries = {boundary("outer", BoundaryType::Fixed), boundary("xaxis", BoundaryType::Roller),
                  boundary("yaxis", BoundaryType::Roller)};

  Simulation sim(build_model(mesh, mats, ifs, c.path), c);
  SolidCharges sc = build_solid_charges(sim.model(), charge_spec(c));
  EXPECT_EQ(sc.block.size(), static_cast<std::size_t>(n_theta));
  sim.add_load([&sc](Model& m, AppliedLoads& out, double t) { solid_loads(m, sc, out, t); });
  sim.limit_dt(sc.dt_limit, "explosive blocks");
  const double t_burn = *std::max_element(sc.t_ign.begin(), sc.t_ign.end()) +
                        *std::max_element(sc.burn_time.begin(), sc.burn_time.end());
  const double t_end = t_burn + 16.0 / omega;
  const GasBody& gb = sc.gas.bodies[0];
  double eps_before = 0;
  bool saved = false;
  while (sim.time() < t_end) {
    sim.step();
    if (!saved && sim.time() >= t_end - 0.1 * (t_end - t_burn)) {
      eps_before = gb.v_cavity / gb.v0 - 1.0;
      saved = true;
    }
  }
  const Model& m = sim.model();
  CavityResult res;
  res.p = gb.pressure;
  res.eps = gb.v_cavity / gb.v0 - 1.0;
  res.vented = gb.vented;
  res.settle = std::abs(res.eps - eps_before) / res.eps;
  // The hole's area from the rock's own wall nodes (the polygon centre - wall vertices), against
  // its initial area: the gas body's cavity must be the rock's hole.
  {
    std::vector<Vec3> now(n_theta + 1), ref(n_theta + 1);
    for (std::size_t n = 0; n < m.n_nodes(); ++n) {
      const auto v = m.node_vertex[n];
      if (v % (nr + 1) != 0 || v >= centre) continue;  // ring 0 (the wall), any block's node
      now[v / (nr + 1)] = m.x[n];
      ref[v / (nr + 1)] = m.X(n);
    }
    double s = 0, s0 = 0;  // the polygon (0,0), wall_0 .. wall_n (the centre is held by rollers)
    for (int j = 0; j < n_theta; ++j) {
      s += 0.5 * cross(now[j], now[j + 1]).z;
      s0 += 0.5 * cross(ref[j], ref[j + 1]).z;
    }
    res.eps_wall = s / s0 - 1.0;
  }
  // The fixed point P = EOS(1 + eps(P)) (bisection: EOS(1 + eps(P)) - P falls with P).
  const double lam = stone.lambda(), g = stone.shear();
  auto eps_of = [&](double p) {
    const double B = p / (2 * g / (a * a) + 2 * (lam + g) / (b * b)), A = -B / (b * b);
    const double ua = A * a + B / a;
    return (1 + ua / a) * (1 + ua / a) - 1;
  };
  res.p0 = eos_pressure(eos, 1.0);
  double lo = 0, hi = res.p0;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (eos_pressure(eos, 1.0 + eps_of(mid)) > mid ? lo : hi) = mid;
  }
  res.p_fix = 0.5 * (lo + hi);
  res.eps_fix = eps_of(res.p_fix);
  res.eps_inf = res.p_fix / g;
  res.blocks = m.n_blocks();
  res.steps = sim.steps();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

// Criteria (the 2 %):
// - eps (the gas body's cavity) within 2 % of the fixed point's. The error is the mesh's (the
//   polygonal hole of n_theta chords and the quads' stiffness) plus the geometric
//   non-linearity (follower pressure, co-rotational blocks: O(eps) = 0.3 %). Measured
//   (GasElasticStudy below): -1.97 % with 6 cells over 90 degrees, -0.40 % with 12, -0.006 %
//   with the 24 used here (a crossing of the two error signs, not a sign of exactness), +0.10 %
//   with 48. 2 % is the error of the 6-cell fan, 5x that of the 12-cell one; it still rejects
//   a wrong compliance of the size of the infinite-medium one (3 %) or a gas volume that missed
//   a block (1 / 24 of the cavity).
// - the pressure drop P0 - P within 2 % of P0 - P_fix (its relative error is eps's, since the
//   adiabat is linear over 3e-3 of volume to 0.3 %); P itself is then within 0.02 % of P_fix,
//   and checked at 2 % only as the issue words it (P ~ P0 whatever the rock does).
// - the gas body's cavity equals the hole the rock's wall nodes enclose (1e-9 relative: the
//   two are sums of the same areas in a different order; tied nodes coincide bitwise).
// - settled: eps changed by less than 2e-3 of itself over the last 10 % of the run.
// - nothing vented (no collar, no cracks, gas = "cavity").
TEST(GasCavity, QuasiStaticCavityMeetsTheAdiabatAndLame) {
  SingleThread one;
  const CavityResult r = run_cavity(24);
  const double d_eps = r.eps / r.eps_fix - 1, d_drop = (r.p0 - r.p) / (r.p0 - r.p_fix) - 1;
  std::printf("[gas cavity] %zu blocks, %lld steps, %.2f s: P %.6g Pa (fixed point %.6g, %+.4f %%; "
              "P0 %.6g), drop P0 - P %+.3f %%; dV/V %.5e (fixed point %.5e, %+.3f %%; infinite "
              "medium %.5e), rock wall dV/V %.5e, settle %.1e, vented %.3g kg\n",
              r.blocks, static_cast<long long>(r.steps), r.wall_s, r.p, r.p_fix,
              100 * (r.p / r.p_fix - 1), r.p0, 100 * d_drop, r.eps, r.eps_fix, 100 * d_eps,
              r.eps_inf, r.eps_wall, r.settle, r.vented);
  EXPECT_NEAR(d_eps, 0.0, 0.02);
  EXPECT_NEAR(d_drop, 0.0, 0.02);
  EXPECT_NEAR(r.p / r.p_fix, 1.0, 0.02);
  EXPECT_NEAR(r.eps_wall / r.eps, 1.0, 1e-9);
  EXPECT_LT(r.settle, 2e-3);
  EXPECT_EQ(r.vented, 0.0);
}

// ---------------------------------------------------------------------------------------------
// 2. Pressurised crack (Sneddon)
// ---------------------------------------------------------------------------------------------
//
// A straight crack |x| < a on y = 0 in a plane-strain plate, its faces under a constant pressure
// p. Sneddon (1946), infinite plate: the opening (both faces) is
//   w(x) = 4 (1 - nu^2) p / E sqrt(a^2 - x^2),
//   w(0) = 4 (1 - nu^2) p a / E,   crack area (per metre)  int w dx = 2 pi (1 - nu^2) p a^2 / E.
// Model: the half x >= 0 (roller on x = 0, the symmetry plane), y in [-L, L], x <= L (L = 20 a),
// the other three sides fixed. Structured quads, square cells of size h = a / n_fine on
// x < 1.25 a, |y| < 0.25 a, growing geometrically (ratio 1.15) to the sides; the crack runs
// along cell edges. Its interfaces (between the rows just below and above y = 0, x < a) are a
// pre-cracked joint (region pair crack_lo / crack_hi); everything else is tied (the conforming
// continuum: no spring compliance).
//
// Load path: update_gas (explosive/gas.cpp), step 3, the gas-in-cracks face loads of the "cracks"
// model: a filled crack (fill 1, body 0) gets +-f P A n on its points' nodes. The body is one gas
// (emulsion products) whose cavity is a reservoir 1e9 times the crack's area, so the crack's own
// volume moves P by ~1e-9 (checked: printed and asserted below 1e-6); P is ramped from 0 to p over
// t_ramp by setting the reservoir's volume on the isentrope (volume_at_pressure), then held. The
// symmetry plane (roller) and the fixed sides are no vents: their face sets are passed to
// init_gas_field as closed, as the charge builders do with the case's boundaries (before that
// fix the crack cells on x = 0 vented 2.56 kg through w x 1 m); the test checks nothing vented.
// A crack with zero aperture takes no gas load (update_gas loads only w > 0, by design: the gas
// needs an opening to enter), and a pre-cracked joint starts exactly closed: the upper crack
// face is moved up by 1e-9 a (1e-6 of the expected opening) before the run.
//
// Damping: c_d = 1.4 omega_est, omega_est = pi c_s sqrt((1 / (2 L))^2 + (1 / (2 L))^2) (the
// plate's lowest shear mode, roller at x = 0 and fixed elsewhere); ramp 4 / omega_est, hold
// 6 / omega_est (shorter than test_lame.cpp's 6 + 8: the crack's opening is carried by modes
// well above the plate's lowest, and every underdamped mode decays as exp(-c_d t / 2); the
// run checks the opening has settled).

struct CrackResult {
  double w0 = 0, w0_ex = 0;        // opening at x = 0 (m), Sneddon
  double area = 0, area_ex = 0;    // int_0^a w dx (half crack, trapezoid over the nodes), Sneddon
  double profile = 0;              // max |w - w_ex| / w0_ex over the crack's nodes
  double settle = 0;               // relative change of w0 over the last 10 % of the run
  double p = 0, p_spread = 0;      // final gas pressure, max |P / p - 1| during the hold
  double vented = 0;
  std::size_t blocks = 0, crack_ifaces = 0;
  std::int64_t steps = 0;
  double wall_s = 0;
};

// Grid lines from 0: cells of h up to `fine` (a multiple of h), then growing by `ratio` until
// `end` (the last cell stretched or merged to end there).
std::vector<double> graded_line(double h, double fine, double ratio, double end) {
  std::vector<double> xs{0.0};
  const int nf = static_cast<int>(std::lround(fine / h));
  for (int i = 1; i <= nf; ++i) xs.push_back(i * h);
  double d = h;
  while (xs.back() < end - 1e-9) {
    d *= ratio;
    xs.push_back(xs.back() + d);
  }
  if (xs.size() > 2 && xs.back() - end > 0.5 * d) xs.pop_back();
  xs.back() = end;
  return xs;
}

CrackResult run_crack(int n_fine, double plate) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double a = 1.0, p = 1e-3 * kE, L = plate * a, h = a / n_fine;
  const std::vector<double> xs = graded_line(h, 1.25 * a, 1.15, L);
  const std::vector<double> yh = graded_line(h, 0.25 * a, 1.15, L);
  std::vector<double> ys;
  for (auto it = yh.rbegin(); it != yh.rend(); ++it) ys.push_back(-*it);
  ys.insert(ys.end(), yh.begin() + 1, yh.end());
  Mesh mesh = graded_quad_grid(xs, ys);
  assign_region(mesh, "crack_lo", [&](Vec3 c) { return c.x < a && c.y < 0 && c.y > -h; });
  assign_region(mesh, "crack_hi", [&](Vec3 c) { return c.x < a && c.y > 0 && c.y < h; });

  const BlockMaterial probe = rock(kE, kNu, kRho);
  const double cs = std::sqrt(probe.shear() / kRho);
  const double omega = kPi * cs * std::sqrt(2.0) / (2 * L), c_d = 1.4 * omega;
  const double t_ramp = 4.0 / omega, t_end = t_ramp + 6.0 / omega;
  BlockMaterial stone = probe;
  stone.regions = {"rock", "crack_lo", "crack_hi"};
  stone.damping = c_d;
  InterfaceMaterial crack = interface_of(InterfaceLaw::MohrCoulomb, 0, 0, 0);
  crack.name = "crack";
  crack.precracked = true;
  crack.is_default = false;
  crack.pairs = {{"crack_lo", "crack_hi"}};
  const std::vector<BlockMaterial> mats{stone};
  const std::vector<InterfaceMaterial> ifs{interface_of(InterfaceLaw::Elastic), crack};
  Case c = make_case(mats, ifs);
  c.path = "test_gas_elastic crack (in-code case)";
  c.interface_mode = InterfaceMode::Tied;
  c.boundaries = {boundary("left", BoundaryType::Roller), boundary("right", BoundaryType::Fixed),
                  boundary("bottom", BoundaryType::Fixed), boundary("top", BoundaryType::Fixed)};
  Model model = build_model(mesh, mats, ifs, c.path);
  // The crack's interfaces, and its vertices' upper and lower nodes.
  std::vector<std::int32_t> crack_ifaces;
  for (std::size_t i = 0; i < model.n_ifaces(); ++i)
    if (model.iface_materials[model.iface_material[i]].name == "crack")
      crack_ifaces.push_back(static_cast<std::int32_t>(i));
  std::map<double, std::pair<std::vector<std::int32_t>, std::vector<std::int32_t>>> faces;  // x
  for (std::size_t n = 0; n < model.n_nodes(); ++n) {
    const Vec3 X = model.X(n);
    if (X.y != 0.0 || X.x > a * (1 + 1e-12)) continue;
    std::int32_t blk = 0;
    while (model.block_first_node[blk + 1] <= static_cast<std::int32_t>(n)) ++blk;
    (centroid0(model, blk).y > 0 ? faces[X.x].second : faces[X.x].first)
        .push_back(static_cast<std::int32_t>(n));
  }
  for (auto& [x, f] : faces)
    if (x < a * (1 - 1e-12))
      for (auto n : f.second) model.x[n].y += 1e-9 * a;  // open the closed crack by a hair

  Simulation sim(std::move(model), c);
  const Eos eos = *builtin_explosive("emulsion");
  const double w0_ex = 4 * (1 - kNu * kNu) * p * a / kE;
  const double v_res = 1e9 * (0.5 * kPi * w0_ex * a);  // reservoir: 1e9 x the half crack's area
  GasField g;
  GasBody body;
  body.model = GasModel::Cracks;
  body.eos = 0;
  body.rho_w = explosive_density(eos);
  g.bodies = {body};
  // Every side of the plate is fixed or a roller (symmetry): none of them vents.
  std::vector<std::string> closed;
  for (const auto& bc : c.boundaries) closed.push_back(bc.faces);
  init_gas_field(sim.model(), g, closed);
  for (auto i : crack_ifaces) {
    g.iface_body[i] = 0;
    g.iface_fill[i] = 1.0f;
  }
  double t_prev = -1, p_target = 0;
  sim.add_load([&](Model& m, AppliedLoads& out, double t) {
    p_target = p * std::clamp(t / t_ramp, 1e-6, 1.0);
    const double v = volume_at_pressure(eos, p_target);  // the reservoir on the isentrope
    g.bodies[0].v0 = v_res / v;
    g.burnt_volume[0] = v_res / v;
    g.cavity[0] = v_res;
    update_gas(m, g, {eos}, out, t_prev >= 0 ? t - t_prev : 0.0);
    t_prev = t;
  });
  auto opening = [&](const std::pair<std::vector<std::int32_t>, std::vector<std::int32_t>>& f) {
    const Model& m = sim.model();
    double lo = 0, hi = 0;
    for (auto n : f.first) lo += m.x[n].y;
    for (auto n : f.second) hi += m.x[n].y;
    return hi / f.second.size() - lo / f.first.size();
  };
  CrackResult res;
  double w0_before = 0;
  bool saved = false;
  while (sim.time() < t_end) {
    sim.step();
    if (sim.time() > t_ramp + 2 * sim.dt())  // (the hook sees the step's start time)
      res.p_spread = std::max(res.p_spread, std::abs(g.bodies[0].pressure / p - 1));
    if (!saved && sim.time() >= t_end - 0.1 * (t_end - t_ramp)) {
      w0_before = opening(faces.begin()->second);
      saved = true;
    }
  }
  res.w0 = opening(faces.begin()->second);
  res.w0_ex = w0_ex;
  res.settle = std::abs(res.w0 - w0_before) / res.w0;
  res.area_ex = 0.25 * kPi * w0_ex * a;  // pi (1 - nu^2) p a^2 / E, the half crack
  double x_prev = 0, w_prev = 0;
  for (const auto& [x, f] : faces) {
    const double w = x < a * (1 - 1e-12) ? opening(f) : 0.0;  // the tip: one cluster, w = 0
    if (x > 0) res.area += 0.5 * (w + w_prev) * (x - x_prev);
    res.profile = std::max(res.profile,
                           std::abs(w - w0_ex * std::sqrt(std::max(0.0, 1 - x * x / (a * a)))) / w0_ex);
    x_prev = x;
    w_prev = w;
  }
  res.p = g.bodies[0].pressure;
  res.vented = g.bodies[0].vented;
  res.blocks = sim.model().n_blocks();
  res.crack_ifaces = crack_ifaces.size();
  res.steps = sim.steps();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("[gas sneddon] a/h = %d, plate %g a: %zu blocks, %zu crack interfaces, %lld steps, "
              "%.2f s: w(0) %.5e m (Sneddon %.5e, %+.3f %%), crack area %.5e m^2 (Sneddon %.5e, "
              "%+.3f %%), profile max |w - w_ex| / w(0) %.3f %%, P %.6g Pa (hold spread %.1e), "
              "settle %.1e, vented %.3g kg\n",
              n_fine, plate, res.blocks, res.crack_ifaces, static_cast<long long>(res.steps),
              res.wall_s, res.w0, res.w0_ex, 100 * (res.w0 / res.w0_ex - 1), res.area, res.area_ex,
              100 * (res.area / res.area_ex - 1), 100 * res.profile, res.p, res.p_spread,
              res.settle, res.vented);
  return res;
}

// Criteria (the 5 %), the plate L = 20 a, cells a / 20 along the crack:
// - the opening at the centre w(0) and the half crack's area int_0^a w dx (trapezoid over the
//   crack's nodes; the tip's vertex is one cluster, w = 0) within 5 % of Sneddon's, and the
//   whole profile within 5 % of w(0) at every node.
//   Measured: w(0) -1.67 %, area -2.88 %, profile 3.2 %. Both errors are the finite plate (its
//   fixed sides stiffen it, O((a / L)^2)) and the mesh (displacement elements are too stiff at
//   the tip's sqrt singularity, O(h)); GasElasticStudy: w(0) -2.82 / -2.23 % with a / h = 20 / 40
//   at L = 10 a, -1.67 / -1.06 % at L = 20 a; area -4.01 / -2.83 % at 10 a, -2.88 / -1.67 % at
//   20 a. 5 % is 1.7x the area's measured error; the 10 a plate of the example would
//   leave only 1 % of margin on the area (-4.0 %), hence 20 a.
// - the gas pressure held at p during the hold (the reservoir: below 1e-6; measured 7e-10),
//   settled (w(0) changed by less than 2e-3 of itself over the last 10 % of the run) and
//   nothing vented.
TEST(GasSneddon, PressurisedCrackOpensAsSneddon) {
  SingleThread one;
  const CrackResult r = run_crack(20, 20.0);
  EXPECT_NEAR(r.w0 / r.w0_ex, 1.0, 0.05);
  EXPECT_NEAR(r.area / r.area_ex, 1.0, 0.05);
  EXPECT_LT(r.profile, 0.05);
  EXPECT_LT(r.p_spread, 1e-6);
  EXPECT_LT(r.settle, 2e-3);
  EXPECT_EQ(r.vented, 0.0);
}

// Studies behind the tolerances (docs/verification_gas.md), not run by default:
// --gtest_also_run_disabled_tests --gtest_filter='*GasElasticStudy*'. The cavity on coarser and
// finer fans; the crack with a finer mesh and with a larger plate (the discretisation and the
// finite plate's share of the error).
TEST(GasElasticStudy, DISABLED_MeshAndPlate) {
  SingleThread one;
  for (int n : {6, 12, 48}) {
    const CavityResult r = run_cavity(n);
    std::printf("[gas cavity study] n_theta %d: dV/V %+.3f %% from the fixed point, drop %+.3f %%\n",
                n, 100 * (r.eps / r.eps_fix - 1), 100 * ((r.p0 - r.p) / (r.p0 - r.p_fix) - 1));
  }
  run_crack(20, 10.0);
  run_crack(40, 10.0);
  run_crack(40, 20.0);
}

}  // namespace
}  // namespace cdem
