// Verification of general contact (SPEC 1.5, physics/contact.hpp; docs/theory.md "General
// contact", numbers in docs/verification_contact.md): head-on impact (momentum, energy,
// penetration, separation), sliding on an incline in 2D and 3D (stick below the friction angle,
// g (sin - mu cos) above), a 200 m/s fragment against a wall (with a tiny skin too), the rebuild
// trigger, a stack settling under gravity, 1 vs 2 threads, and a released pair caught again.
#include <array>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <utility>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <span>
#include <cstdlib>
#include <string>
#include <vector>

#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/contact.hpp"
#include "cdem/solver/simulation.hpp"
#include "verification/model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;

// Appends mesh b to mesh a (a separate body: no shared vertices); b's region and face set names
// get `suffix`.
Mesh merge(Mesh a, const Mesh& b, const std::string& suffix) {
  const auto nv = static_cast<std::int32_t>(a.vertices.size());
  const auto nr = static_cast<std::int32_t>(a.region_names.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const auto& r : b.region_names) a.region_names.push_back(r + suffix);
  for (std::size_t e = 0; e < b.num_elements(); ++e) {
    a.elem_type.push_back(b.elem_type[e]);
    auto v = b.elem_vertices[e];
    for (auto& x : v)
      if (x >= 0) x += nv;
    a.elem_vertices.push_back(v);
    a.elem_region.push_back(b.elem_region[e] + nr);
    a.elem_tag.push_back(static_cast<std::int64_t>(a.elem_tag.size() + 1));
  }
  for (auto fs : b.face_sets) {
    fs.name += suffix;
    for (auto& f : fs.facets)
      for (auto& x : f.v)
        if (x >= 0) x += nv;
    a.face_sets.push_back(fs);
  }
  return a;
}

Mesh body(int dim, int n, double size, Vec3 origin) {
  return dim == 3 ? tet_box(n, n, n, size, size, size, origin) : quad_grid(n, n, size, size, origin);
}

Case contact_case(const std::vector<BlockMaterial>& mats, const InterfaceMaterial& im,
                  double friction) {
  Case c = make_case(mats, {im});
  c.contact.enabled = true;
  c.contact.friction = friction;
  return c;
}

// Mean velocity (mass-weighted) and position of the blocks of region r.
struct BodyState {
  Vec3 v, x;
  double mass = 0;
};
BodyState body_state(const Model& m, int region) {
  BodyState s;
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    if (m.block_region[b] != region) continue;
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
      s.mass += m.mass[n];
      s.v += m.mass[n] * m.v[n];
      s.x += m.mass[n] * m.x[n];
    }
  }
  s.v = s.v / s.mass;
  s.x = s.x / s.mass;
  return s;
}

// Two cubes (edge `size`, 2 x 2 (x 2) cells, regions a and b, unbreakable inside), b's corner at
// x = bx and shifted sideways by `offset` (0.7 x that in z), a moving at +v0 along x, b at -v0.
struct TwoCubes {
  BlockMaterial mat_a = rock(1e10, 0.25, 2500, "a"), mat_b = rock(1e10, 0.25, 2500, "b");
  InterfaceMaterial glue = interface_of(InterfaceLaw::Elastic);
  Model model;
  // frictionless contact, no damping
  Case contact() const { return contact_case({mat_a, mat_b}, glue, 0.0); }
};
TwoCubes two_cubes(int dim, double size, double bx, double offset, double v0) {
  TwoCubes t;
  Mesh mesh = merge(body(dim, 2, size, {0, 0, 0}), body(dim, 2, size, {bx, offset, dim == 3 ? 0.7 * offset : 0.0}), "");
  mesh.region_names = {"a", "b"};
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) mesh.elem_region[e] = e < mesh.num_elements() / 2 ? 0 : 1;
  t.model = build_model(mesh, {t.mat_a, t.mat_b}, {t.glue}, "two_cubes");
  for (std::size_t n = 0; n < t.model.n_nodes(); ++n)
    t.model.v[n] = {t.model.block_region[t.model.node_block(n)] == 0 ? v0 : -v0, 0, 0};
  return t;
}

// ---------------------------------------------------------------------------------------------
// Head-on impact of two cubes (0.1 m, 2 x 2 x 2 Kuhn cells, or 2 x 2 quads) at +-1 m/s across a
// 1 mm gap, frictionless, unbreakable interfaces, no damping:
//  - momentum: contact forces are equal and opposite (the node's F, the face nodes' -w F with
//    sum w = 1), so the total momentum is conserved to round-off: 1e-10 of sum m |v|;
//  - penetration: the impact stress is rho c_p v (two bodies at relative speed 2v: the
//    interface moves at 0, each side sees v), shared by the contact nodes of the face
//    (area A / nodes) against their stiffness k: d = rho c_p v A_node / k. Checked at most 2 x
//    that (the penalty spring overshoots the quasi-static share during the first contact wave);
//  - energy: kinetic + strain after the bodies separate within 2 % of the initial kinetic
//    energy (the rest goes to the contact's switching and stays booked: the balance error is
//    checked at 1 %). The second body is offset sideways by 0.13 of a cell: with the two meshes
//    exactly aligned every contact node lands on a vertex of the other body, inside all the
//    blocks around it, the degenerate case of node-to-face contact, where the contact moves
//    from block to block of the other body (the takeover in contact.cpp); that case is run too,
//    measured 2D -2.5 %, 3D -0.1 %, checked within 5 % (before the takeover carried the
//    penetration over, 3D was +24 %: energy from nothing; docs/verification_contact.md);
//  - contact never makes energy: its booked dissipation (switching, friction) stays above
//    -1e-4 of the initial energy (room for the trapezoidal work estimate's O((omega dt)^2) terms
//    over the few hundred contact steps; measured +7.9e-4 to +2.5e-2, all losses);
//  - the bodies separate (their mean velocities reverse).
// ---------------------------------------------------------------------------------------------
void impact(int dim, double offset) {
  const double size = 0.1, gap = 1e-3, v0 = 1.0;
  TwoCubes cubes = two_cubes(dim, size, size + gap, offset, v0);
  const BlockMaterial mat_a = cubes.mat_a;
  Simulation sim(std::move(cubes.model), cubes.contact());
  auto momentum = [&]() {
    Vec3 p{};
    double s = 0;
    for (std::size_t n = 0; n < sim.model().n_nodes(); ++n) {
      p += sim.model().mass[n] * sim.model().v[n];
      s += sim.model().mass[n] * norm(sim.model().v[n]);
    }
    return std::make_pair(p, s);
  };
  const auto [p0, s0] = momentum();
  sim.step(true);
  const double e0 = sim.energy().mechanical();
  double pen = 0, max_err = 0, dp = 0;
  const double t_end = 3 * size / mat_a.cp() + gap / v0;  // impact + a few wave transits
  while (sim.time() < t_end) {
    sim.step(true);
    max_err = std::max(max_err, sim.energy().error);
    dp = std::max(dp, norm(momentum().first - p0));
    for (double g : sim.contact().pair_gap) pen = std::max(pen, g);
  }
  // run on until they are apart
  while (sim.time() < 3 * t_end) sim.step(true);
  const EnergyBalance e = sim.energy();
  const double e_after = e.kinetic + e.block_strain + e.spring_strain;
  const BodyState a = body_state(sim.model(), 0), b = body_state(sim.model(), 1);
  const double k = sim.contact().pair_k.empty() ? 0 : sim.contact().pair_k.front();
  const double a_node = dim == 3 ? size * size / 9.0 : size / 3.0;  // face area per face node
  const double d_bound = mat_a.density * mat_a.cp() * v0 * a_node / k;
  std::printf("[contact impact] %dD offset %.3g m: dt %.3g s, %lld steps, %lld rebuilds: momentum drift %.2e, "
              "max penetration %.3g m (bound %.3g m, %.2e of the block size), energy after / "
              "before %.4f, contact dissipation %.2e of it, balance error max %.2e, mean velocities %.3f / %.3f m/s\n",
              dim, offset, sim.dt(), static_cast<long long>(sim.steps()),
              static_cast<long long>(sim.contact().rebuilds), dp / s0, pen, d_bound, pen / size,
              e_after / e0, e.contact_friction / e0, max_err, a.v.x, b.v.x);
  EXPECT_LT(dp, 1e-10 * s0);
  EXPECT_GT(pen, 0.0);
  EXPECT_LT(pen, 2 * d_bound);
  EXPECT_NEAR(e_after / e0, 1.0, offset == 0.0 ? 0.05 : 0.02);
  EXPECT_GT(e.contact_friction, -1e-4 * e0);
  EXPECT_LT(max_err, 0.01);
  EXPECT_LT(a.v.x, 0.0);  // bounced back
  EXPECT_GT(b.v.x, 0.0);
  EXPECT_LT(a.x.x + 0.5 * size, b.x.x - 0.5 * size + 1e-9);  // apart
  // where the largest penetration was reached (summary.json): between the two bodies, on the
  // plane they meet on (x = size + gap / 2, the impact being symmetric) within the penetration
  // bound, after the gap closed (at gap / 2 v0) and before the end of the impact phase
  const auto& at = sim.contact().max_pen_at;
  const Model& m = sim.model();
  ASSERT_GE(at.block, 0);
  const std::int32_t other = at.node >= 0 ? m.node_block(static_cast<std::size_t>(at.node)) : at.other;
  EXPECT_NE(m.block_region[at.block], m.block_region[other]);
  EXPECT_NEAR(at.x.x, size + 0.5 * gap, 2 * d_bound + 1e-9);
  EXPECT_GT(at.time, 0.5 * gap / v0);
  EXPECT_LT(at.time, t_end);
  std::printf("[contact impact] largest penetration %.3g of the block size at t = %.3g s, %s, x = %.5f m\n",
              sim.contact().max_pen_ratio, at.time, at.node >= 0 ? "node against face" : "edge crossing", at.x.x);
}

TEST(ContactImpact, HeadOn2D) { impact(2, 0.0); impact(2, 0.013); }
TEST(ContactImpact, HeadOn3D) { impact(3, 0.0); impact(3, 0.013); }

// ---------------------------------------------------------------------------------------------
// A first touch pushes back no more than the approach (contact.cpp, (c); contact_edges.cpp;
// docs/verification_contact.md, "The deep-touch test"). Two cubes as in the impact test, offset
// sideways as its second case (no node on a vertex), overlapping when contact first sees them:
//  - deep: by 30 % of a cell (15 mm, ~300 x the blocks' tolerance, ~1 000-2 000 steps' approach),
//    as nodes that sank in while a broken point held them, or that fly into a block through faces
//    that were not candidates yet. Such a node did not just arrive: none of its depth is pushed
//    back (pushing two steps' approach back each time the node was taken up as new made 1.2 MJ
//    and threw a node at 1.1 km/s in coarse SPEC 5.3 scheme A);
//  - shallow: by 30 um, less than two steps' approach plus the tolerance, the depth a node that
//    does arrive has; moving apart nothing of it is approach (with |v_n| for the approach, all
//    of it was pushed back, throwing the cubes apart faster).
// Moving apart at +-v0 (v0 = 1 m/s): no contact force at any step (node forces at round-off, no
// edge force), so the kinetic energy and the speeds stay the initial ones to 1e-12.
// Moving together (deep only): no force at the first step; they bounce on the depth they add,
// not on the one they came in with: kinetic + strain energy after the bounce within 2 % of
// before (the impact test's bound), the contacts' booked dissipation above -1 % of it (below),
// and they separate.
// ---------------------------------------------------------------------------------------------
void deep_touch(int dim, double v0, double overlap) {
  const double size = 0.1;
  TwoCubes cubes = two_cubes(dim, size, size - overlap, 0.013, v0);  // v0 > 0: towards each other
  const BlockMaterial mat_a = cubes.mat_a;
  const Model& model = cubes.model;
  double e0 = 0;  // the kinetic energy at the start (no strain yet)
  for (std::size_t n = 0; n < model.n_nodes(); ++n) e0 += 0.5 * model.mass[n] * dot(model.v[n], model.v[n]);
  Simulation sim(std::move(cubes.model), cubes.contact());
  // the largest contact force of the node-to-face pairs and of the edge pairs
  auto largest = [&](const std::vector<Vec3>& forces) {
    double f = 0;
    for (const Vec3& F : forces) f = std::max(f, norm(F));
    return f;
  };
  sim.step(true);
  const double f_first = std::max(largest(sim.contact().pair_force), largest(sim.contact().ec_force));
  std::int64_t held_first = 0;
  for (auto kf : sim.contact().pair_kf) held_first += kf >= 0;
  ASSERT_GT(held_first, 0);  // the overlap is seen as contact at once
  const double k = *std::min_element(sim.contact().pair_k.begin(), sim.contact().pair_k.end());
  double f_node = 0, f_edge = 0;
  // together: the bounce and a few wave transits; apart: twice the time they take to part
  const double t_run = v0 > 0 ? 9 * size / mat_a.cp() : overlap / -v0 + 3 * size / mat_a.cp();
  while (sim.time() < t_run) {
    sim.step(true);
    f_node = std::max(f_node, largest(sim.contact().pair_force));
    f_edge = std::max(f_edge, largest(sim.contact().ec_force));
  }
  const EnergyBalance e = sim.energy();
  const double e_after = e.kinetic + e.block_strain + e.spring_strain;
  const BodyState a = body_state(sim.model(), 0), b = body_state(sim.model(), 1);
  std::printf("[contact deep touch] %dD, %s at %.3g m/s, %.3g m deep: %lld contacts taken up at the "
              "first step, largest force then %.3g N; over the run node pairs %.3g N (k x %.3g m), "
              "edge pairs %.3g N; energy after / before %.12f, contact dissipation %.2e of it; mean "
              "velocities %.4f / %.4f m/s\n",
              dim, v0 > 0 ? "together" : "apart", std::abs(v0), overlap, static_cast<long long>(held_first),
              f_first, f_node, f_node / k, f_edge, e_after / e0, e.contact_friction / e0, a.v.x, b.v.x);
  EXPECT_EQ(f_first, 0.0);  // nothing of the overlap is pushed back
  if (v0 < 0) {
    // Moving apart, nothing is pushed: the node forces are round-off of the ignored depth (g
    // recomputed each step), below k x 1e-15 m, and no edge crossing takes a force (the edges
    // that sweep through each other as the overlap closes are inside an overlap the node
    // contacts ignore: contact_edges.cpp; before 6 Dec they held the cubes together, -10 % of
    // the kinetic energy). So the bodies fly apart untouched: kinetic energy and speeds stay
    // the initial ones to 1e-12 (free flight of unstressed bodies).
    EXPECT_LT(f_node, 1e-15 * k);
    EXPECT_EQ(f_edge, 0.0);
    EXPECT_NEAR(e_after / e0, 1.0, 1e-12);
    EXPECT_NEAR(a.v.x, v0, 1e-12);
    EXPECT_NEAR(b.v.x, -v0, 1e-12);
  } else {
    // Together: the bounce on the depth they add. Energy after within 2 % of before (the impact
    // test's bound; measured 2D 1.0060, 3D 1.0009). The contacts' booked dissipation is
    // negative here (2D -6.0e-3, 3D -9.2e-4 of the energy): the four symmetric corner nodes
    // leave their contact in one step at the end of the bounce, each releasing its last step's
    // spring in one step (the central difference's switching error, in phase for all four), not a
    // push-back. Bounded by 1 % of the energy: well below what a push-back of two steps'
    // approach made here (+4.5 % in 3D apart; 2D together: a force at the first step).
    EXPECT_GT(f_node, 0.0);
    EXPECT_NEAR(e_after / e0, 1.0, 0.02);
    EXPECT_GT(e.contact_friction, -1e-2 * e0);
    EXPECT_LT(a.v.x, 0.0);  // bounced back
    EXPECT_GT(b.v.x, 0.0);
  }
}

TEST(ContactDeepTouch, PushesNothingBack2D) {
  deep_touch(2, -1.0, 0.015);
  deep_touch(2, 1.0, 0.015);
  deep_touch(2, -1.0, 3e-5);
}
TEST(ContactDeepTouch, PushesNothingBack3D) {
  deep_touch(3, -1.0, 0.015);
  deep_touch(3, 1.0, 0.015);
  deep_touch(3, -1.0, 3e-5);
}

// ---------------------------------------------------------------------------------------------
// Passivity (contact.cpp, "Passivity"): a node's debt, the energy its contacts made, is taken
// back by a dashpot on its next contact steps, and no more. The 3D head-on impact (frictionless,
// no damping, offset 0.13 of a cell) is run four times:
//  - plain: passivity on, no debt (the reference);
//  - in debt: the same with a debt put on each contact node of cube a before it strikes, 2 % of
//    the initial kinetic energy in all (as if its contacts had made that): at the end the debt is
//    paid (what is left is what the last exits made, as in the plain run, where the contacts that
//    ended last made 0.3 % of e0 that no later contact takes back; the impact lasts ~100 contact
//    steps, the dashpot takes up to a quarter of the relative normal speed per step), and the
//    contacts' booked dissipation is up by about the debt (measured 0.90 of it: the impact's own
//    switching losses count against the debt too), the kinetic + strain energy after down by
//    the same;
//  - passivity off, with and without that debt: bitwise the same motion (the key turns the
//    controller off, debts and all).
// ---------------------------------------------------------------------------------------------
struct DebtRun {
  double e0 = 0, e_after = 0, diss = 0, debt_left = 0, debt_put = 0;
  std::vector<Vec3> x;
};
DebtRun debt_run(bool passivity, double debt_share) {
  const double size = 0.1, gap = 1e-3, v0 = 1.0;
  TwoCubes cubes = two_cubes(3, size, size + gap, 0.013, v0);
  Case c = cubes.contact();
  c.contact.passivity = passivity;
  Simulation sim(std::move(cubes.model), c);
  sim.step(true);
  DebtRun r;
  r.e0 = sim.energy().mechanical();
  // cube a's contact nodes (of its candidate faces) on its face at x = size that strike b's face
  // (within b's face, which is offset by (0.013, 0.0091) m: a node outside it meets nothing and
  // can pay nothing)
  std::vector<std::size_t> face;
  for (const std::int32_t n : sim.contact().cand_nodes) {
    const Vec3 x = sim.model().x[static_cast<std::size_t>(n)];
    if (sim.model().block_region[sim.model().node_block(static_cast<std::size_t>(n))] == 0 &&
        std::abs(x.x - size) < 1e-4 && x.y > 0.013 + 1e-3 && x.z > 0.0091 + 1e-3)
      face.push_back(static_cast<std::size_t>(n));
  }
  for (std::size_t n : face) sim.contact().node_debt[n] = debt_share * r.e0 / static_cast<double>(face.size());
  r.debt_put = debt_share * r.e0;
  const double t_end = 3 * (3 * size / cubes.mat_a.cp() + gap / v0);
  while (sim.time() < t_end) sim.step(true);
  const EnergyBalance e = sim.energy();
  r.e_after = e.kinetic + e.block_strain + e.spring_strain;
  r.diss = e.contact_friction;
  for (double d : sim.contact().node_debt) r.debt_left += d;
  r.x = sim.model().x;
  std::printf("[contact passivity] %s, debt put %.3e J (%zu nodes): energy after / before %.5f, booked "
              "contact dissipation %.4e J, debts left %.3e J\n",
              passivity ? "passivity" : "without", r.debt_put, face.size(), r.e_after / r.e0, r.diss, r.debt_left);
  return r;
}

TEST(ContactPassivity, TakesBackTheDebtNoMore) {
  const double share = 0.02;
  const DebtRun plain = debt_run(true, 0.0), in_debt = debt_run(true, share);
  const double d = in_debt.debt_put;
  EXPECT_NEAR(in_debt.debt_left, plain.debt_left, 0.1 * d);
  // taken back: no more than the debt (10 % for the dashpot's last step, booked half at the next,
  // and the changed switching), no less than the debt less what the impact's own switching
  // dissipated meanwhile (booked against the debt: the plain run's whole contact dissipation
  // bounds it) and 5 % more
  const double taken = in_debt.diss - plain.diss;
  EXPECT_LT(taken, 1.1 * d);
  EXPECT_GT(taken, d - plain.diss - 0.05 * d);
  EXPECT_NEAR(plain.e_after - in_debt.e_after, taken, 0.05 * d);  // and it is the motion's
  const DebtRun off = debt_run(false, 0.0), off_debt = debt_run(false, share);
  ASSERT_EQ(off.x.size(), off_debt.x.size());
  EXPECT_EQ(std::memcmp(off.x.data(), off_debt.x.data(), off.x.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(off.diss, off_debt.diss);
}

// ---------------------------------------------------------------------------------------------
// A held node that changes face takes no new depth with it (contact.cpp, (c): the face change).
// At a block's edge or vertex a node is behind two or three face planes at once, within the
// block's tolerance tol (1e-3 of its size) of each; the face it is in contact with can then change
// while it is held. The depth it had pushed on the old face carries on to the new one, no more:
// before, the ignored depth d0, worn down on the old face, was applied to the new face's depth,
// and the difference was pushed back at once: energy from nothing at each change. A node on the
// vertex of a block of its own body (cracked faces as candidates) switched between two faces every
// second step that way, 3-13 kJ each time, until coarse SPEC 5.3 scheme B stopped at 7.02 ms
// (docs/verification_contact.md).
// Here the apex of a heavy tet (its motion imposed: 0.2 m/s down and up, 10^6 x the rock's
// density so that the contact does not slow it) goes into the top face of a fixed cube 0.3 tol
// from the cube's side face (x = 0): it comes in through the top face (the faster approach) and
// is held by it; on its way out, once above the top face's plane but still within tol of it (so
// inside the block), the side face, behind which it lies 0.3 tol deep, holds it: a face change
// while held, three times (three strokes). Each change must not deepen the pair's pushed depth
// (gap after <= gap before, to 1e-12 of tol: the new d0 is computed from the same doubles), and
// the changes must happen (the test sees the case it is for). Before the fix the gap jumped from
// about 0 to 0.3 tol at each change.
// ---------------------------------------------------------------------------------------------
TEST(ContactFaceChange, HeldNodeTakesNoNewDepth) {
  const double s = 0.1, v = 0.2;
  Mesh mesh = tet_box(1, 1, 1, s, s, s);
  // the Kuhn tet (000, 001, 011, 111) of the cube has the faces x = 0 and z = s, meeting along
  // the edge x = 0, z = s; the apex goes in at y = s/2 (far from its other two faces)
  // the blocks' tolerance (contact.cpp: 1e-3 of the block's size; the cube's six tets are alike)
  const double tol = 1e-3 * make_model(mesh, rock(), interface_of(InterfaceLaw::Elastic)).block_size[0];
  const double x0 = 0.3 * tol, y0 = 0.5 * s, z0 = s + 2 * tol, h = 0.3 * s;
  // apex down, its top face level (positive orientation: the apex, then the top face clockwise
  // seen from above)
  Mesh tip = single_element(ElemType::Tet4, {{x0, y0, z0}, {x0 + h, y0 - h, z0 + h}, {x0, y0 + h, z0 + h},
                                             {x0 - h, y0 - h, z0 + h}});
  mesh = merge(mesh, tip, "_tip");
  mesh.region_names = {"cube", "tip"};
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) mesh.elem_region[e] = e < 6 ? 0 : 1;
  const std::vector<BlockMaterial> mats = {rock(1e10, 0.25, 2500, "cube"), rock(1e10, 0.25, 2.5e9, "tip")};
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Case c = contact_case(mats, glue, 0.0);
  BoundaryCondition fix;
  fix.faces = "bottom";
  fix.type = BoundaryType::Fixed;
  c.boundaries = {fix};
  Model model = build_model(mesh, mats, {glue}, "face_change");
  const auto tip_block = static_cast<std::int32_t>(model.n_blocks() - 1);
  Simulation sim(std::move(model), c);
  const std::int32_t apex = sim.model().block_first_node[tip_block];  // the tip's node 0
  ASSERT_NEAR(sim.model().x[apex].z, z0, 1e-15);
  const Vec3 down{0, 0, -v};
  Vec3 vel = down;
  int strokes = 0, changes = 0;
  double worst = 0, deepest = 0;
  std::vector<std::int8_t> kf_before;
  std::vector<double> gap_before;
  std::vector<std::int32_t> node_before, block_before;
  while (strokes < 3 && sim.steps() < 100000) {
    const double z = sim.model().x[apex].z;
    if (vel.z < 0 && z < s - 0.5 * tol) vel = -1.0 * down;  // 0.5 tol deep: back up
    if (vel.z > 0 && z > s + 2 * tol) vel = down, ++strokes;
    for (auto n = sim.model().block_first_node[tip_block]; n < sim.model().block_first_node[tip_block + 1]; ++n)
      sim.model().v[n] = vel;
    const ContactSet& cs = sim.contact();
    kf_before = cs.pair_kf, gap_before = cs.pair_gap, node_before = cs.pair_node, block_before = cs.pair_block;
    sim.step(true);
    if (cs.pair_node != node_before || cs.pair_block != block_before) continue;  // a rebuild
    for (std::size_t p = 0; p < cs.pair_node.size(); ++p) {
      deepest = std::max(deepest, cs.pair_gap[p]);
      if (kf_before[p] < 0 || cs.pair_kf[p] < 0 || cs.pair_kf[p] == kf_before[p]) continue;
      ++changes;
      worst = std::max(worst, cs.pair_gap[p] - gap_before[p]);
    }
  }
  const EnergyBalance e = sim.energy();
  std::printf("[contact face change] %d strokes, %lld steps, %d face changes while held, largest "
              "gap growth at a change %.3g tol, deepest pushed gap %.3g tol, contact "
              "dissipation %.3g J\n",
              strokes, static_cast<long long>(sim.steps()), changes, worst / tol, deepest / tol,
              e.contact_friction);
  EXPECT_EQ(strokes, 3);
  EXPECT_GE(changes, 3);  // one per stroke at least: the case this test is for
  EXPECT_LE(worst, 1e-12 * tol);
  // The energy booked as dissipated by the contacts: with the motion imposed, the only bookings
  // below zero are the three arrivals (a new contact pushes back two steps' approach, of which
  // the step's motion did work for one: -k (v dt)^2 each, contact.cpp); the rest is the held
  // springs' (zero to round-off: the trapezoid rule is exact for a linear spring on one face) and
  // the drops (+ the stored energy). Measured +3.97e-3 J; before the fix -9.57e-2 J.
  const double k = *std::max_element(sim.contact().pair_k.begin(), sim.contact().pair_k.end());
  EXPECT_GE(e.contact_friction, -3 * k * (v * sim.dt()) * (v * sim.dt()));
}

// ---------------------------------------------------------------------------------------------
// A block resting on a fixed base, gravity tilted by theta (the same as an incline of slope
// theta), friction mu = 0.5 (tan 26.6 deg). theta = 20 deg: it sticks (mean speed along the slope
// after 40 ms below 1 mm/s: the elastic settling only). theta = 40 deg: it slides with
// a = g (sin theta - mu cos theta) = 2.552 m/s^2, measured from its mean velocity between 10 and
// 40 ms (after the settling onto the base) within 2 %: the friction force is mu F_n at every
// sliding contact node, and the normal forces sum to m g cos theta once the bounce has died out
// (light contact damping, zeta = 0.2, removes the bounce without a drag along the slope).
// ---------------------------------------------------------------------------------------------
double incline(int dim, double theta_deg) {
  const double size = 0.1, mu = 0.5, gval = 9.81;
  const auto base_m = rock(1e10, 0.25, 2500, "base");
  const auto blk_m = rock(1e10, 0.25, 2500, "block");
  Mesh mesh = merge(body(dim, 2, size, {0, 0, 0}), body(dim, 1, 0.5 * size, {0.25 * size, dim == 3 ? 0.25 * size : size, dim == 3 ? size : 0}), "_blk");
  mesh.region_names = {"base", "block"};
  const std::size_t nbase = dim == 3 ? 48 : 4;
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) mesh.elem_region[e] = e < nbase ? 0 : 1;
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Case c = contact_case({base_m, blk_m}, glue, mu);
  c.contact.damping_ratio = 0.2;
  const double th = theta_deg * kPi / 180;
  c.gravity = dim == 3 ? Vec3{gval * std::sin(th), 0, -gval * std::cos(th)}
                       : Vec3{gval * std::sin(th), -gval * std::cos(th), 0};
  BoundaryCondition fix;
  fix.faces = "bottom";
  fix.type = BoundaryType::Fixed;
  c.boundaries = {fix};
  Simulation sim(build_model(mesh, {base_m, blk_m}, {glue}, "incline"), c);
  double v10 = 0;
  while (sim.time() < 0.04) {
    sim.step();
    if (v10 == 0 && sim.time() >= 0.01) v10 = body_state(sim.model(), 1).v.x;
  }
  const double v40 = body_state(sim.model(), 1).v.x;
  const double a = (v40 - v10) / (sim.time() - 0.01);
  const double expect = std::max(0.0, gval * (std::sin(th) - mu * std::cos(th)));
  std::printf("[contact incline] %dD theta %.0f deg: speed at 40 ms %.4g m/s, acceleration %.4f "
              "m/s^2 (expected %.4f), %lld steps, max contact pairs %lld\n",
              dim, theta_deg, v40, a, expect, static_cast<long long>(sim.steps()),
              static_cast<long long>(sim.contact().active_max));
  return theta_deg < 26 ? v40 : a / expect;
}

TEST(ContactFriction, Incline2D) {
  EXPECT_LT(std::abs(incline(2, 20)), 1e-3);
  EXPECT_NEAR(incline(2, 40), 1.0, 0.02);
}
TEST(ContactFriction, Incline3D) {
  EXPECT_LT(std::abs(incline(3, 20)), 1e-3);
  EXPECT_NEAR(incline(3, 40), 1.0, 0.02);
}

// ---------------------------------------------------------------------------------------------
// A 5 cm fragment at 200 m/s towards a fixed wall 1 cm away: it must not pass through, with the
// default skin and with a skin of 1e-4 m (1/50 of the distance it covers in a step, so the list
// is rebuilt every step). Its leading face stays in front of the wall's face to within the
// penetration bound (2 x rho c v A_node / k, as the impact test) and it leaves at negative speed.
// ---------------------------------------------------------------------------------------------
void fast_fragment(double skin) {
  const double wall = 0.2, frag = 0.05, v0 = 200.0;
  const auto wm = rock(1e10, 0.25, 2500, "wall");
  const auto fm = rock(1e10, 0.25, 2500, "frag");
  Mesh mesh = merge(tet_box(2, 2, 2, wall, wall, wall, {0, 0, 0}),
                    tet_box(1, 1, 1, frag, frag, frag, {-frag - 0.01, 0.075, 0.075}), "_f");
  mesh.region_names = {"wall", "frag"};
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) mesh.elem_region[e] = e < 48 ? 0 : 1;
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Case c = contact_case({wm, fm}, glue, 0.0);
  c.contact.skin = skin;
  BoundaryCondition fix;
  fix.faces = "right";
  fix.type = BoundaryType::Fixed;
  c.boundaries = {fix};
  Model model = build_model(mesh, {wm, fm}, {glue}, "fragment");
  for (std::size_t n = 0; n < model.n_nodes(); ++n)
    if (model.block_region[model.node_block(n)] == 1) model.v[n] = {v0, 0, 0};
  Simulation sim(std::move(model), c);
  double lead = -1e9;
  while (sim.time() < 4 * (0.01 / v0)) {
    sim.step();
    for (std::size_t n = 0; n < sim.model().n_nodes(); ++n)
      if (sim.model().block_region[sim.model().node_block(n)] == 1) lead = std::max(lead, sim.model().x[n].x);
  }
  const double k = sim.contact().pair_k.empty() ? 1.0 : sim.contact().pair_k.front();
  const double bound = 2 * fm.density * fm.cp() * v0 * (frag * frag / 4) / k;
  const BodyState f = body_state(sim.model(), 1);
  std::printf("[contact fragment] skin %.3g m: %lld rebuilds in %lld steps (%.3g m per step), "
              "deepest point of the fragment %.4g m past the wall face (bound %.3g m), speed after "
              "%.2f m/s\n",
              sim.contact().skin, static_cast<long long>(sim.contact().rebuilds),
              static_cast<long long>(sim.steps()), v0 * sim.dt(), lead, bound, f.v.x);
  EXPECT_LT(lead, bound);
  EXPECT_LT(f.v.x, 0.0);
  if (skin == 0.0) {
    // each block's own skin: the fragment's raised at the first build (all its nodes at v0) to
    // what it covers in kSkinSteps steps, at most kSkinCap reference skins; the wall's as set up
    const ContactSet& cs = sim.contact();
    EXPECT_EQ(cs.rebuilds, 1);
    int raised = 0;
    for (std::size_t b = 0; b < sim.model().n_blocks(); ++b) {
      const double want = sim.model().block_region[b] == 1
                              ? std::max(cs.half_skin0[b], std::min(v0 * kSkinSteps * sim.dt(), kSkinCap * cs.skin))
                              : cs.half_skin0[b];
      EXPECT_DOUBLE_EQ(cs.half_skin[b], want) << "block " << b;
      raised += cs.half_skin[b] > cs.half_skin0[b];
    }
    EXPECT_EQ(raised, 6) << "the fragment's six tetrahedra";
  }
}

TEST(ContactFast, FragmentAt200MetresPerSecond) {
  fast_fragment(0.0);
  fast_fragment(1e-4);
}

// The rebuild trigger itself: a candidate node moved by 0.49 skin leaves the list; by 0.51 skin
// it is rebuilt at the next contact_forces call; released points rebuild once the relative
// motion bound since the release passes 0.1 skin: the bound of the nodes near the released
// block (within 2 skins of its box), or, for all others, 2.1 skins of 2 max|v| dt
// (contact_release.cpp).
TEST(ContactFast, RebuildTrigger) {
  const auto mat = rock();
  const auto glue = interface_of(InterfaceLaw::Elastic);
  // a 4 x 1 x 1 m bar of 1 m cubes, 6 tetrahedra each: its two ends are 2 m apart
  Model m = make_model(tet_box(4, 1, 1, 4, 1, 1), mat, glue);
  ContactSettings cfg;
  cfg.enabled = true;
  cfg.skin = 0.01;
  ContactSet cs = setup_contact(m, cfg, 1.0, 1e10);
  contact_forces(m, cs, 1e-6);
  ASSERT_EQ(cs.rebuilds, 1);
  // n: a candidate node at the x = 0 end
  std::int32_t n = -1;
  for (const std::int32_t c : cs.cand_nodes)
    if (m.x[c].x < 1e-9) n = c;
  ASSERT_GE(n, 0);
  m.x[n].x += 0.49 * cfg.skin;
  contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 1);
  m.x[n].x += 0.02 * cfg.skin;  // now 0.51 skin from where it was at the build
  contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 2);
  // a point released on an interface: of n's block, or of two blocks beyond x = 3 m
  auto release_point = [&](bool near_n) {
    const std::int32_t bn = m.node_block(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      const std::int32_t a = m.iface_block_a[i], b = m.iface_block_b[i];
      bool far = true;
      for (const std::int32_t k : {a, b}) {
        Vec3 lo, hi;
        m.block_box(static_cast<std::size_t>(k), lo, hi);
        far = far && lo.x > 3.0 - 1e-9;
      }
      const std::size_t sp = i * static_cast<std::size_t>(m.springs_per_iface);
      if ((near_n ? (a == bn || b == bn) : far) && m.sp_state[sp] != kReleased) {
        m.sp_state[sp] = kReleased;
        ++m.released_points;
        return;
      }
    }
    FAIL() << "no interface to release";
  };
  // At rest: no rebuild, whatever the steps.
  release_point(true);
  for (int k = 0; k < 5; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 2);
  // n moving at 100 m/s, dt = 1e-6 s: 2e-4 m = 0.02 skin per step: 0.10 skin after 5 steps,
  // beyond at the 6th (the bound may have grown by a hair less than 0.1 skin at the 5th by
  // rounding).
  for (std::size_t q = 0; q < m.n_nodes(); ++q) m.v[q] = Vec3{0.0, 0.0, 0.0};
  m.v[n] = Vec3{100.0, 0.0, 0.0};
  for (int k = 0; k < 4; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 2) << "rebuilt before the nodes could have moved 0.1 skin";
  contact_forces(m, cs, 1e-6);
  contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 3) << "not rebuilt once the nodes could have moved 0.1 skin";
  EXPECT_EQ(cs.release_drift, 0.0);
  // A point released 2 m from n, the blocks near it at rest: n is no nearer than 2 m - 0.02 m
  // after 99 steps (2.08 skins of 2 max|v| dt: n and the released faces approach by at most
  // that), so no rebuild; the far bound passes 2.1 skins at the 106th step.
  release_point(false);
  for (int k = 0; k < 100; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 3) << "a fast node 2 m away rebuilt the pairs of a released block";
  EXPECT_EQ(cs.release_drift, 0.0) << "the released block's neighbourhood is at rest";
  for (int k = 0; k < 10; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 4) << "not rebuilt once any node could have reached the released faces";
  // A checkpoint written before the neighbourhood existed (no near marks): the old rule, the
  // fastest node anywhere, until the next build.
  release_point(false);
  contact_forces(m, cs, 1e-6);
  cs.blk_near.clear();
  for (int k = 0; k < 4; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 4);
  contact_forces(m, cs, 1e-6);
  contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 5) << "the old rule: rebuilt once any node could have moved 0.1 skin";
  // A release that splits the body in two (every point of every interface across x = 3 m), 2 m
  // from n: the two parts' nodes and blocks may pair anywhere they touch, so the old rule.
  contact_forces(m, cs, 1e-6);
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    Vec3 la, ha, lb, hb;
    m.block_box(static_cast<std::size_t>(m.iface_block_a[i]), la, ha);
    m.block_box(static_cast<std::size_t>(m.iface_block_b[i]), lb, hb);
    if (std::min(la.x, lb.x) > 3.0 - 1e-9 || std::max(ha.x, hb.x) < 3.0 + 1e-9) continue;  // (one side)
    for (int q = 0; q < m.springs_per_iface; ++q) {
      const std::size_t sp = i * static_cast<std::size_t>(m.springs_per_iface) + static_cast<std::size_t>(q);
      if (m.sp_state[sp] != kReleased) m.sp_state[sp] = kReleased, ++m.released_points;
    }
  }
  for (int k = 0; k < 4; ++k) contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 5);
  contact_forces(m, cs, 1e-6);
  contact_forces(m, cs, 1e-6);
  EXPECT_EQ(cs.rebuilds, 6) << "a release that splits a body: the old rule";
  std::int32_t far_block = -1;
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    Vec3 lo, hi;
    m.block_box(b, lo, hi);
    if (lo.x > 3.0 - 1e-9) far_block = static_cast<std::int32_t>(b);
  }
  ASSERT_GE(far_block, 0);
  EXPECT_NE(cs.body[m.node_block(static_cast<std::size_t>(n))], cs.body[far_block]) << "the body was not split";
}

// Each block's own skin (the default, skin = 0): a graded pair of bodies, a coarse 1 m cube of
// 0.5 m tetrahedra and a fine 0.2 m cube of 0.05 m ones 1 cm beside it.
// - Every block's half skin is 0.125 x its size (its box's largest extent).
// - The grid search is exact: the pairs listed are those of a list built with one skin larger
//   than any (a superset), kept where the node lies within sigma_n + sigma_b of the block's box
//   (the same test written out here, pair by pair).
// - The trigger is per node: a node of the fine body rebuilds after moving past its own sigma_n;
//   a node of the coarse body moved as far does not, and does past its larger sigma_n; a node of
//   a candidate block that is on none of its candidate faces rebuilds past its block's sigma.
TEST(ContactFast, EachBlocksOwnSkin) {
  const auto mat = rock();
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Mesh mesh = merge(tet_box(2, 2, 2, 1, 1, 1), tet_box(4, 4, 4, 0.2, 0.2, 0.2, {1.01, 0.4, 0.4}), "_f");
  mesh.region_names = {"rock"};  // (one region: two bodies, no vertex shared)
  for (auto& r : mesh.elem_region) r = 0;
  Model m = make_model(mesh, mat, glue);
  ContactSettings cfg;
  cfg.enabled = true;
  ContactSet cs = setup_contact(m, cfg, 1.0, 1e10);
  ASSERT_EQ(cs.half_skin.size(), m.n_blocks());
  for (std::size_t b = 0; b < m.n_blocks(); ++b) EXPECT_EQ(cs.half_skin[b], 0.125 * block_extent(m, b));
  contact_forces(m, cs, 1e-6);
  ASSERT_EQ(cs.rebuilds, 1);
  ContactSettings wide = cfg;
  wide.skin = 1.0;  // (more than twice the largest half skin: every pair above is in its list)
  ContactSet cw = setup_contact(m, wide, 1.0, 1e10);
  contact_forces(m, cw, 1e-6);
  std::vector<std::pair<std::int32_t, std::int32_t>> expect, got;
  for (std::size_t p = 0; p < cw.pair_node.size(); ++p) {
    const std::int32_t n = cw.pair_node[p], b = cw.pair_block[p];
    const double g = cs.half_skin[b] + cs.half_skin[m.node_block(static_cast<std::size_t>(n))];
    Vec3 lo, hi;
    m.block_box(static_cast<std::size_t>(b), lo, hi);
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && m.x[n][d] >= lo[d] - g && m.x[n][d] <= hi[d] + g;
    if (in) expect.emplace_back(n, b);
  }
  for (std::size_t p = 0; p < cs.pair_node.size(); ++p) got.emplace_back(cs.pair_node[p], cs.pair_block[p]);
  EXPECT_EQ(got, expect);
  EXPECT_GT(got.size(), 0u);
  EXPECT_LT(got.size(), cw.pair_node.size());
  std::printf("[contact skin] half skins %.4g to %.4g m: %zu pairs, %zu with one skin of 1 m\n",
              *std::min_element(cs.half_skin.begin(), cs.half_skin.end()),
              *std::max_element(cs.half_skin.begin(), cs.half_skin.end()), got.size(), cw.pair_node.size());
  // The trigger: a candidate node of each body.
  std::int32_t fine = -1, coarse = -1;
  for (auto n : cs.cand_nodes)  // (the blocks may be renumbered: told apart by their size)
    (cs.half_skin[m.node_block(static_cast<std::size_t>(n))] > 0.03 ? coarse : fine) = n;
  ASSERT_GE(fine, 0);
  ASSERT_GE(coarse, 0);
  auto sigma = [&](std::int32_t n) { return cs.half_skin[m.node_block(static_cast<std::size_t>(n))]; };
  ASSERT_LT(2 * sigma(fine), sigma(coarse));
  // moves node n by `times` the half skin of node `of`'s block along axis d, then one step's
  // trigger: the rebuilds so far
  auto move = [&](std::int32_t n, double times, std::int32_t of, int d) {
    m.x[n][d] += times * sigma(of);
    contact_forces(m, cs, 1e-6);
    return cs.rebuilds;
  };
  EXPECT_EQ(move(coarse, 1.01, fine, 2), 1) << "a coarse node rebuilt on the fine body's skin";
  EXPECT_EQ(move(fine, 0.99, fine, 2), 1);
  EXPECT_EQ(move(fine, 0.02, fine, 2), 2) << "a fine node moved past its own half skin, not rebuilt";
  EXPECT_EQ(move(coarse, 0.99, coarse, 2), 2);  // (from where it was at the second build)
  EXPECT_EQ(move(coarse, 0.02, coarse, 2), 3) << "a coarse node moved past its own half skin, not rebuilt";
  // A node of a candidate block off its candidate faces (the block stretches): watched too.
  ASSERT_FALSE(cs.watch_nodes.empty());
  const std::int32_t w = cs.watch_nodes.front();
  EXPECT_FALSE(std::binary_search(cs.cand_nodes.begin(), cs.cand_nodes.end(), w));
  EXPECT_EQ(move(w, 0.99, w, 1), 3);
  EXPECT_EQ(move(w, 0.02, w, 1), 4) << "a candidate block's other node moved past its half skin, not rebuilt";
}

// ---------------------------------------------------------------------------------------------
// A stack of three 5 cm cubes 1 mm apart above a fixed base, under gravity, contact damping
// zeta = 0.3 and Cundall's local damping alpha_L = 0.3 (the settling option of SPEC 1.4; the
// contact dashpots alone leave the stack rocking on its point contacts): they fall, settle and
// stay. Aligned stack: the kinetic energy after 0.15 s below 1e-6 of the potential energy
// released, the heights constant to 1 um over the last 20 ms, penetrations below 1e-4 of the
// size (m g / k per node is ~1e-8 m), every cube above the one below it. The same stack with the
// cubes shifted sideways by 0.13 of their size, held by the same bounds: there each cube rests
// on two vertices of a diagonal and on two crossings of edges, and before edge-to-edge contact
// (contact_edges.cpp) it rocked about that diagonal and kept sliding at a few cm/s (kinetic
// 1.8 % of the energy released at 0.15 s); with it, it comes to rest like the aligned stack.
// ---------------------------------------------------------------------------------------------
struct StackResult {
  double kinetic_ratio = 0, dz = 0, pen = 0;
  bool ordered = true;
};
StackResult stack(double shift) {
  const double s = 0.05, gap = 1e-3;
  std::vector<BlockMaterial> mats;
  Mesh mesh = tet_box(2, 2, 1, 2 * s, 2 * s, s, {-0.5 * s, -0.5 * s, -s});
  mesh.region_names = {"base"};
  for (int k = 0; k < 3; ++k)
    mesh = merge(mesh, tet_box(1, 1, 1, s, s, s, {shift * s * (k % 2), 0.5 * shift * s * k, gap + k * (s + gap)}),
                 std::to_string(k));
  for (const auto& r : mesh.region_names) {
    mats.push_back(rock(1e10, 0.25, 2500, r));
    mats.back().local_damping = 0.3;
  }
  const auto glue = interface_of(InterfaceLaw::Elastic);
  Case c = contact_case(mats, glue, 0.6);
  c.contact.damping_ratio = 0.3;
  c.gravity = {0, 0, -9.81};
  BoundaryCondition fix;
  fix.faces = "bottom";
  fix.type = BoundaryType::Fixed;
  c.boundaries = {fix};
  Simulation sim(build_model(mesh, mats, {glue}, "stack"), c);
  std::vector<double> z_late;
  while (sim.time() < 0.15) {
    sim.step(true);
    if (z_late.empty() && sim.time() >= 0.13)
      for (int r = 1; r <= 3; ++r) z_late.push_back(body_state(sim.model(), r).x.z);
  }
  const EnergyBalance e = sim.energy();
  StackResult res;
  for (int r = 1; r <= 3; ++r)
    res.dz = std::max(res.dz, std::abs(body_state(sim.model(), r).x.z - z_late[r - 1]));
  for (double g : sim.contact().pair_gap) res.pen = std::max(res.pen, g);
  for (int r = 1; r < 3; ++r)
    res.ordered = res.ordered &&
                  body_state(sim.model(), r + 1).x.z > body_state(sim.model(), r).x.z + 0.99 * s;
  res.kinetic_ratio = e.kinetic / std::abs(e.gravity_work);
  std::printf("[contact stack] shift %.2f: kinetic %.3g of the energy released, height change over "
              "the last 20 ms %.3g m, max penetration %.3g m, %lld pairs in contact, energy error "
              "%.2e\n",
              shift, res.kinetic_ratio, res.dz, res.pen, static_cast<long long>(sim.contact().active),
              e.error);
  return res;
}

TEST(ContactStack, SettlesUnderGravity) {
  const double s = 0.05;
  const StackResult aligned = stack(0.0);
  EXPECT_LT(aligned.kinetic_ratio, 1e-6);
  EXPECT_LT(aligned.dz, 1e-6);
  EXPECT_LT(aligned.pen, 1e-4 * s);
  EXPECT_TRUE(aligned.ordered);
  const StackResult shifted = stack(0.13);
  EXPECT_LT(shifted.kinetic_ratio, 1e-6);
  EXPECT_LT(shifted.dz, 1e-6);
  EXPECT_LT(shifted.pen, 1e-4 * s);
  EXPECT_TRUE(shifted.ordered);
}

// ---------------------------------------------------------------------------------------------
// 1 vs 2 threads with contact active (the 3D impact): positions, velocities, forces and the
// contact state bitwise identical.
// ---------------------------------------------------------------------------------------------
// Two bodies of 48 tets, 0.1 m cubes ("a" at the origin, "b" beyond it across x by `gap`,
// shifted by `dy`), each glued inside by a Mohr-Coulomb interface of tensile strength ft.
auto two_bodies(double gap, double dy, double ft, const std::string& name) {
  const double size = 0.1;
  const auto mat_a = rock(1e10, 0.25, 2500, "a"), mat_b = rock(1e10, 0.25, 2500, "b");
  Mesh mesh = merge(body(3, 2, size, {0, 0, 0}), body(3, 2, size, {size + gap, dy, 0}), "");
  mesh.region_names = {"a", "b"};
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) mesh.elem_region[e] = e < 48 ? 0 : 1;
  const auto glue = interface_of(InterfaceLaw::MohrCoulomb, ft, 3 * ft, 30);
  return std::make_tuple(build_model(mesh, {mat_a, mat_b}, {glue}, name), mat_a, mat_b, glue);
}

// The 3D impact with the thread count of each step given by threads_at(step) (set-up at that of
// step 0).
auto impact_run(const std::function<int(int)>& threads_at, bool sleep = true,
                std::array<std::int64_t, 3>* tests = nullptr, double gap = 1e-3, double skin = 0,
                double va = 5.0, double vb = -5.0) {
  ScopedThreads th(threads_at(0));
  const auto [model_ab, mat_a, mat_b, glue] = two_bodies(gap, 0.02, 1e5, "impact");
  Model model = model_ab;
  for (std::size_t n = 0; n < model.n_nodes(); ++n)
    model.v[n] = {model.block_region[model.node_block(n)] == 0 ? va : vb, 0.3, 0};
  Case c = contact_case({mat_a, mat_b}, glue, 0.4);
  c.contact.sleep = sleep;
  if (skin > 0) c.contact.skin = skin;
  Simulation sim(std::move(model), c);
  for (int k = 0; k < 300; ++k) {
    omp_set_num_threads(threads_at(k));
    sim.step(k % 7 == 0);
  }
  if (tests) *tests = {sim.contact().pair_tests, sim.contact().block_pair_tests, sim.contact().rebuilds};
  return std::make_tuple(sim.model().x, sim.model().v, sim.contact().pair_force,
                         sim.contact().active_max, sim.energy().contact_friction);
}

// Two runs of impact_run: contact happened, and positions, velocities, contact forces and the
// friction dissipation are the same bits.
template <class R>
void expect_same_impact(const R& a, const R& b) {
  EXPECT_GT(std::get<3>(a), 0) << "no contact";
  EXPECT_TRUE(same_bits(std::get<0>(a), std::get<0>(b)));
  EXPECT_TRUE(same_bits(std::get<1>(a), std::get<1>(b)));
  EXPECT_TRUE(same_bits(std::get<2>(a), std::get<2>(b)));
  EXPECT_EQ(std::memcmp(&std::get<4>(a), &std::get<4>(b), sizeof(double)), 0);
}

// The sleep of far pairs (contact.cpp, contact_edges.cpp) skips only tests that could not have
// found anything: the 3D impact (tetrahedra, the glue breaking, fragments hitting: both the
// node-block and the block-pair sleep at work) with every pair tested every step gives the same
// bits, and the sleep did skip most tests (else this would compare nothing). A sleep 10 times too
// long on the face planes, of the node-block pairs or of the block pairs, fails it (the block
// pairs' bounding spheres here overlap before their blocks come near: a longer sphere sleep
// passes). With a skin of 2 mm the pairs are rebuilt many times as the bodies close the gap:
// the pairs that stay keep their sleep across a rebuild (contact_broad_phase.cpp), and that
// changes nothing either.
TEST(ContactDeterminism, SleepChangesNothing) {
  for (const double skin : {0.0, 0.002}) {
    std::array<std::int64_t, 3> slept{}, awake{};
    // (a gap of 1 cm, a fifth of a block, closed at 10 m/s within the run: pairs across it are
    // found apart, sleep, and wake as the bodies come together)
    const auto a = impact_run([](int) { return 2; }, true, &slept, 0.01, skin);
    const auto b = impact_run([](int) { return 2; }, false, &awake, 0.01, skin);
    expect_same_impact(a, b);
    EXPECT_LT(2 * slept[0], awake[0]) << "node-block tests: " << slept[0] << " of " << awake[0];
    EXPECT_LT(2 * slept[1], awake[1]) << "block-pair tests: " << slept[1] << " of " << awake[1];
    EXPECT_EQ(slept[2], awake[2]);
    if (skin > 0) {
      EXPECT_GE(slept[2], 3) << "rebuilds: " << slept[2];
    }
    std::printf("[contact sleep] skin %s: node-block tests %lld of %lld, block-pair tests %lld of %lld, %lld rebuilds\n",
                skin > 0 ? "2 mm" : "default", static_cast<long long>(slept[0]), static_cast<long long>(awake[0]),
                static_cast<long long>(slept[1]), static_cast<long long>(awake[1]), static_cast<long long>(slept[2]));
  }
}

// The pairs sleep on their node's group clock (contact.cpp), which must follow the pairs' blocks
// too: body a (blocks 0-47, groups 0-2) drifts sideways at 0.3 m/s only and is struck by body b
// (blocks 48-95, groups 3-5) at 10 m/s, so a's nodes come into b's faces while a's own groups move
// 33 times slower. Sleep on (at 1, 2 and 3 threads, so that threads' ranges start inside groups)
// or off: the same bits, with the default skin (one build) and a 2 mm skin (rebuilds, the wakes
// kept across them while the groups' lists change). (Built with a clock that followed only its
// own group's nodes, this fails: a's nodes slept through b's approach.)
TEST(ContactDeterminism, SleepClockFollowsThePairsBlocks) {
  for (const double skin : {0.0, 0.002}) {
    std::array<std::int64_t, 3> slept{}, awake{};
    const auto b = impact_run([](int) { return 2; }, false, &awake, 0.01, skin, 0.0, -10.0);
    for (const int threads : {1, 2, 3}) {
      const auto a = impact_run([threads](int) { return threads; }, true, &slept, 0.01, skin, 0.0, -10.0);
      expect_same_impact(a, b);
    }
    EXPECT_LT(2 * slept[0], awake[0]) << "node-block tests: " << slept[0] << " of " << awake[0];
    if (skin > 0) {
      EXPECT_GE(slept[2], 3) << "rebuilds: " << slept[2];
    }
  }
}

// The sleep does not wear out over a long run. Body a spins at 50 rad/s about the x axis through
// its centre, 1 cm from body b (at rest) across x: its face towards b turns in its own plane, so
// the pairs across the gap stay apart, while a's nodes travel paths of different lengths (0 to
// 3.5 m/s). A block's drift bound was the spread of its nodes' path lengths (max_i D_i(t) -
// min_i D_i(t0)), which grows with the run and, once past the gap, woke the pairs every step
// (built so, this fails: 34 % of the node-block and of the block-pair tests of the run without
// sleep); the path length of the block's fastest node (blk_drift, contact.cpp) wakes them only as
// often as that path could close the gap (0.5 % and 1.1 %). Over 1 500 steps (6.1 ms) with and
// without the sleep: the same bits, and fewer than a tenth of the tests.
TEST(ContactDeterminism, SleepDoesNotWearOut) {
  auto run = [](bool sleep, std::array<std::int64_t, 3>& tests) {
    ScopedThreads th(2);
    const double size = 0.1, omega = 50;
    const auto [model_ab, mat_a, mat_b, glue] = two_bodies(0.01, 0.0, 1e7, "spin");
    Model model = model_ab;
    const Vec3 c{0.5 * size, 0.5 * size, 0.5 * size};
    for (std::size_t n = 0; n < model.n_nodes(); ++n) {
      const Vec3 r = model.x[n] - c;
      model.v[n] = model.block_region[model.node_block(n)] == 0 ? Vec3{0, -omega * r.z, omega * r.y} : Vec3{};
    }
    Case cs = contact_case({mat_a, mat_b}, glue, 0.4);
    cs.contact.sleep = sleep;
    Simulation sim(std::move(model), cs);
    for (int k = 0; k < 1500; ++k) sim.step(k % 50 == 0);
    tests = {sim.contact().pair_tests, sim.contact().block_pair_tests, sim.contact().rebuilds};
    return std::make_pair(sim.model().x, sim.time());
  };
  std::array<std::int64_t, 3> slept{}, awake{};
  const auto a = run(true, slept), b = run(false, awake);
  EXPECT_TRUE(same_bits(a.first, b.first));
  std::printf("[contact sleep, long run] %.3g ms: node-block tests %lld of %lld, block-pair tests %lld of %lld, %lld rebuilds\n",
              1e3 * a.second, static_cast<long long>(slept[0]), static_cast<long long>(awake[0]),
              static_cast<long long>(slept[1]), static_cast<long long>(awake[1]), static_cast<long long>(slept[2]));
  EXPECT_GT(awake[0], 0);
  EXPECT_LT(10 * slept[0], awake[0]);
  EXPECT_LT(10 * slept[1], awake[1]);
}

TEST(ContactDeterminism, ImpactOneAndTwoThreads) {
  const auto a = impact_run([](int) { return 1; }), b = impact_run([](int) { return 2; });
  expect_same_impact(a, b);
}

// The thread count changing between steps, as a run's thread governor changes it
// (solver/thread_governor.hpp): set up on 1 thread, then 2 and 1 in turns of 37 steps, against 2
// threads throughout. Bitwise identical, and no per-thread buffer sized at a build with fewer
// threads is overrun (the near list's counts were, before they were resized on growth).
TEST(ContactDeterminism, ThreadCountChangingBetweenSteps) {
  const auto a = impact_run([](int k) { return k == 0 ? 1 : (k / 37) % 2 ? 1 : 2; });
  const auto b = impact_run([](int) { return 2; });
  expect_same_impact(a, b);
}

// ---------------------------------------------------------------------------------------------
// A released pair that comes back together: two stacked quads (0.1 m) joined by a weak
// Mohr-Coulomb interface, the lower one fixed at its base; the upper one is launched upward at
// 2.5 m/s under a gravity of 50 m/s^2. It breaks the interface in tension, rises some 4 cm
// (beyond the release distance, here 0.2 x 0.1 m: the points are released), falls back and
// lands.
// The contact catches it: its lowest point never goes below the lower block's top by more than
// the impact penetration bound (2 x rho c v A_node / k, as above) and it bounces; the contact
// force grows from zero at the touch, so no step changes it by more than the penalty spring's
// own rate, k v dt per contact node (two in 2D), with a factor 3 for the elastic ringing.
// ---------------------------------------------------------------------------------------------
TEST(ContactHandover, ReleasedPairCaughtAgain) {
  const double s = 0.1, v0 = 2.5, gval = 50.0;
  const auto mat = rock(1e10, 0.25, 2500);
  auto weak = interface_of(InterfaceLaw::MohrCoulomb, 1e3, 3e3, 30);
  Mesh mesh = quad_grid(1, 2, s, 2 * s);
  Case c = contact_case({mat}, weak, 0.3);
  c.gravity = {0, -gval, 0};
  c.release_distance_factor = 0.2;  // released 2 cm apart (the block rises ~4 cm)
  BoundaryCondition fix;
  fix.faces = "bottom";
  fix.type = BoundaryType::Fixed;
  c.boundaries = {fix};
  Model model = make_model(mesh, mat, weak);
  for (std::size_t n = 0; n < model.n_nodes(); ++n)
    if (model.X(model.block_first_node[model.node_block(n)]).y > 0.5 * s) model.v[n] = {0, v0, 0};
  Simulation sim(std::move(model), c);
  double max_jump = 0, prev = 0, lowest = 1e9, k = 0, top = 0;
  bool released = false, caught = false;
  const double t_flight = 2 * v0 / gval;
  while (sim.time() < 1.3 * t_flight) {
    sim.step();
    const Model& m = sim.model();
    for (auto st : m.sp_state) released = released || st == kReleased;
    double fy = 0;
    for (const auto& f : sim.contact().pair_force) fy += std::abs(f.y);
    if (fy > 0 && released) caught = true, k = sim.contact().pair_k.front();
    if (released) max_jump = std::max(max_jump, std::abs(fy - prev));
    for (std::size_t b = 0; b < m.n_blocks(); ++b) {
      const bool upper = m.X(m.block_first_node[b]).y > 0.5 * s;
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
        if (upper && released) lowest = std::min(lowest, m.x[n].y);
        if (!upper) top = std::max(top, m.x[n].y);
      }
    }
  }
  const double bound = 2 * mat.density * mat.cp() * v0 * (s / 2) / (k > 0 ? k : 1.0);
  const BodyState up = body_state(sim.model(), 0);
  std::printf("[contact handover] released %d, caught %d: lowest point of the upper block %.5g m "
              "(lower block's top %.5g m, bound %.3g m), largest per-step change of the contact "
              "force %.3g N (3 x 2 k v dt = %.3g N)\n",
              released, caught, lowest, top, bound, max_jump, 3 * 2 * k * v0 * sim.dt());
  (void)up;
  EXPECT_TRUE(released);
  EXPECT_TRUE(caught);
  EXPECT_GT(lowest, s - bound);
  EXPECT_LT(max_jump, 3 * 2 * k * v0 * sim.dt());
}

// ---------------------------------------------------------------------------------------------
// Faces that turn apart release their broken points (simulation.release_angle, springs.cpp
// broken_release). Two blocks share one interface: two quads (2D), or two tets sharing a face
// (3D); the upper block is given a rigid spin of 100 rad/s about a hinge on the shared face (its
// left edge's end in 2D, one edge of the face in 3D), so the interface breaks in tension and the
// points on the hinge stay within 1-2 cm of their partners while the faces turn apart. (A
// broken point is a contact along the mean normal of its two faces; coarse SPEC 5.3 scheme B had
// two tumbling tets whose faces were 177 degrees apart, where that normal is rounding, and their
// last broken point made 5.8 MJ: docs/verification_contact.md.)
//  - default (0.5 rad, the release distance factor as a rotation): the hinge points are released
//    at the step at which the faces' angle has passed 28.65 degrees, not before (the angle is
//    measured here from the positions the step's spring update sees);
//  - release_angle = 180 (the method paper's rule, release by distance only): at 45 degrees
//    (asserted reached) they are still broken, not released;
//  - both modes of the core (tied, springs). The release distance is 1 x the block size here,
//    so that the hinge points (which slide ~1 cm by 28.65 degrees and up to ~5 cm by 45 as the
//    free block spins about its centre of mass) are not released by distance first.
// (The largest force a broken point carries is printed, not asserted: in the tied mode it is the
// first step's, where the tie meets the spin's velocity jump across it and breaks.)
// ---------------------------------------------------------------------------------------------
struct TurnResult {
  double angle_before = -1, angle_at = -1;  // degrees: the last step's angle before the release
  double angle_end = -1;                    // degrees: the angle at the end of the run
  bool released = false;
  bool hinge_broken = true;                 // every hinge point broken (not intact) at the end
  double max_force = 0;
};
TurnResult turning_faces(int dim, InterfaceMode mode, double release_angle, double end_angle) {
  const double s = 0.1, omega = 100.0;
  Mesh mesh;
  Vec3 hinge, axis;
  if (dim == 2) {
    mesh = quad_grid(1, 2, s, 2 * s);
    hinge = {0, s, 0};
    axis = {0, 0, 1};
  } else {
    mesh.dim = 3;
    mesh.region_names = {"rock"};
    mesh.vertices = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}, {0.3 * s, 0.3 * s, -s}};
    // shared face (0, 1, 2) at z = 0: a below, b above; hinge: the edge 0-1 (the x axis)
    mesh.elem_type = {ElemType::Tet4, ElemType::Tet4};
    mesh.elem_vertices = {{0, 2, 1, 4}, {0, 1, 2, 3}};
    mesh.elem_region = {0, 0};
    mesh.elem_tag = {1, 2};
    hinge = {0, 0, 0};
    axis = {1, 0, 0};  // turns b's far corner (y = s) upwards, opening the face
  }
  const auto mat = rock(1e10, 0.25, 2500);
  const auto weak = interface_of(InterfaceLaw::MohrCoulomb, 1.0, 1.0, 30);
  Case c = contact_case({mat}, weak, 0.3);
  c.interface_mode = mode;
  c.release_angle = release_angle;
  c.release_distance_factor = 1.0;  // (0.1 m: the hinge points are not released by distance)
  Model model = make_model(mesh, mat, weak);
  // b: the upper block (2D: y above the hinge; 3D: the second tet)
  auto upper = [&](const Model& m, std::size_t b) {
    Vec3 cen{};
    const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
    for (auto n = n0; n < n1; ++n) cen += m.X(n);
    cen = cen / static_cast<double>(n1 - n0);
    return dim == 2 ? cen.y > s : cen.z > 0;
  };
  for (std::size_t b = 0; b < model.n_blocks(); ++b)
    if (upper(model, b))
      for (auto n = model.block_first_node[b]; n < model.block_first_node[b + 1]; ++n)
        model.v[n] = omega * cross(axis, model.X(n) - hinge);
  Simulation sim(std::move(model), c);
  const int np = sim.model().springs_per_iface;
  // the faces' angle (degrees) of the one interface between the blocks, as broken_release
  // measures it
  auto angle = [&](const Model& m) {
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      if (upper(m, m.iface_block_a[i]) == upper(m, m.iface_block_b[i])) continue;
      Vec3 pa[3], pb[3];
      for (int q = 0; q < np; ++q) pa[q] = m.x[m.sp_a[i * np + q]], pb[q] = m.x[m.sp_b[i * np + q]];
      const Vec3 aa = face_area_vector(std::span<const Vec3>(pa, np), np),
                 ab = face_area_vector(std::span<const Vec3>(pb, np), np);
      return std::acos(std::clamp(dot(aa, ab) / std::sqrt(dot(aa, aa) * dot(ab, ab)), -1.0, 1.0)) *
             180.0 / std::numbers::pi;
    }
    return -1.0;
  };
  TurnResult r;
  double a_prev = angle(sim.model());
  // (a cap: 100 rad/s turns 45 degrees in ~8 ms, a few hundred steps)
  for (int step = 0; step < 100000 && a_prev < end_angle && !r.released; ++step) {
    sim.step();
    const Model& m = sim.model();
    r.hinge_broken = true;
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      if (upper(m, m.iface_block_a[i]) == upper(m, m.iface_block_b[i])) continue;
      for (int q = 0; q < np; ++q) {
        const auto sidx = i * np + q;
        if (m.sp_state[sidx] == kBroken)
          r.max_force = std::max(r.max_force, std::abs(m.sp_fn[sidx]) + norm(m.sp_fs[sidx]));
        // a point on the hinge (the far ones may go by distance)
        const Vec3 h = m.X(m.sp_a[sidx]) - hinge;
        if (norm(h - dot(h, axis) * axis) < 1e-9 * s) {
          if (m.sp_state[sidx] == kReleased) r.released = true;
          if (m.sp_state[sidx] != kBroken) r.hinge_broken = false;
        }
      }
    }
    // (the step's spring update sees the positions after the step's move: its angle is this one)
    const double a = angle(m);
    r.angle_end = a;
    if (r.released) {
      r.angle_before = a_prev;
      r.angle_at = a;
      break;
    }
    a_prev = a;
  }
  return r;
}

TEST(ContactHandover, TurnedFacesReleaseBrokenPoints) {
  const double theta_r = 0.5 * 180.0 / std::numbers::pi;
  for (int dim : {2, 3})
    for (auto mode : {InterfaceMode::Tied, InterfaceMode::Springs}) {
      const auto r = turning_faces(dim, mode, theta_r, 60.0);
      std::printf("[turned faces] %dD %s: released at %.3f deg (the step before: %.3f), largest "
                  "force of a broken point %.3g N\n",
                  dim, name_of(mode), r.angle_at, r.angle_before, r.max_force);
      EXPECT_TRUE(r.released);
      EXPECT_GE(r.angle_at, theta_r);
      EXPECT_LT(r.angle_before, theta_r);
      const auto paper = turning_faces(dim, mode, 180.0, 45.0);
      std::printf("[turned faces] %dD %s, release_angle = 180: at %.3f deg released %d, every hinge "
                  "point broken %d\n",
                  dim, name_of(mode), paper.angle_end, paper.released, paper.hinge_broken);
      EXPECT_GE(paper.angle_end, 45.0);
      EXPECT_FALSE(paper.released);
      EXPECT_TRUE(paper.hinge_broken);
    }
}

}  // namespace
}  // namespace cdem
