// The vectorised spring kernel (spring_forces: chunks of interfaces, SIMD over interfaces and
// spring points, a vector path for intact spring points under a linear law and one for broken
// ones in contact, the rest one at a time) against the reference form that updates one spring
// point at a time (spring_forces_reference). Both evaluate the same expressions in the same
// order, so the state after every step must be equal bit for bit: F_n, F_s, w, slip, dilation,
// state, mode, break time, dissipation and the interface normals.
//
// The state is driven hard enough to exercise every branch: a per-vertex random velocity field
// (strain rates that break spring points in tension and shear within the steps run), 20 % of the
// interfaces pre-cracked (contact and friction, some separating beyond the release distance),
// each law (elastic, Mohr-Coulomb, fracture energy), with and without an in-situ preload
// offset g0, in 3D (tets, 3 spring points per interface) and 2D (triangles, 2); and in the tied
// mode (the default of a case), where both forms work on the active interfaces only and skip
// the tied points: the pre-cracked interfaces untied, and one point of a further 15 % of the
// interfaces untied while intact (an opened point: the fast path, or the fracture-energy law).
// The kernel divided between two ranks of a distributed run (each its share of the list, then
// the shares exchanged as packed state) gives the same bits too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cdem/physics/springs.hpp"
#include "cdem/physics/ties.hpp"
#include "model_builders.hpp"

namespace cdem {
namespace {

using namespace test_models;

struct Counts {
  std::size_t broken = 0, released = 0, intact = 0;
  std::size_t by_angle = 0;  // points released within the release distance: by the angle
};

// The spring state of two models: the names of the arrays that differ in any bit.
std::string differing(const Model& m, const Model& ref) {
  std::string differ;
  auto check = [&differ](bool eq, const char* what) {
    if (!eq) differ += std::string(" ") + what;
  };
  check(same_bits(m.sp_fn, ref.sp_fn), "sp_fn");
  check(same_bits(m.sp_fs, ref.sp_fs), "sp_fs");
  check(same_bits(m.sp_w, ref.sp_w), "sp_w");
  check(same_bits(m.sp_slip, ref.sp_slip), "sp_slip");
  check(same_bits(m.sp_dil, ref.sp_dil), "sp_dil");
  check(same_bits(m.sp_state, ref.sp_state), "sp_state");
  check(same_bits(m.sp_mode, ref.sp_mode), "sp_mode");
  check(same_bits(m.sp_break_time, ref.sp_break_time), "sp_break_time");
  check(same_bits(m.sp_dissipated, ref.sp_dissipated), "sp_dissipated");
  check(same_bits(m.iface_normal, ref.iface_normal), "iface_normal");
  return differ;
}

// A distributed run's division of the kernel (Simulation::share_springs), on two "ranks" a and
// b: each steps its share of the list (a cut off a chunk boundary), then each packs its share
// and the other unpacks it (pack_spring_state, unpack_spring_state).
void ranked_spring_step(Model& a, Model& b, double dt, double t) {
  const auto n = static_cast<std::int64_t>(a.tied ? a.active_ifaces.size() : a.n_ifaces());
  const std::int64_t mid = std::min<std::int64_t>(n, n / 2 + 7);
  spring_forces(a, dt, t, 0, mid);
  spring_forces(b, dt, t, mid, n);
  const int d = spring_state_doubles(a);
  std::vector<double> buf(static_cast<std::size_t>(n * d));
  const std::int32_t* la = a.tied ? a.active_ifaces.data() : nullptr;
  const std::int32_t* lb = b.tied ? b.active_ifaces.data() : nullptr;
  pack_spring_state(a, la, 0, mid, buf.data());
  unpack_spring_state(b, lb, 0, mid, buf.data());
  pack_spring_state(b, lb, mid, n, buf.data() + mid * d);
  unpack_spring_state(a, la, mid, n, buf.data() + mid * d);
}

Counts run_pair(bool three_d, InterfaceLaw law, bool preload, bool tied) {
  const Mesh mesh = three_d ? tet_box(7, 6, 5, 0.7, 0.6, 0.5) : tri_grid(16, 14, 1.6, 1.4);
  InterfaceMaterial im = interface_of(law, 2e6, 4e6, 30, 10);
  im.gt = 20;
  im.gs = 200;
  im.residual_friction_deg = 20;
  Model m = make_model(mesh, rock(), im);
  m.release_cos = std::cos(0.5);  // the release angle's default (Simulation sets it from the case)
  // Pre-cracked interfaces and an optional preload offset.
  std::mt19937_64 gen(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int np = m.springs_per_iface;
  for (std::size_t i = 0; i < m.n_ifaces(); ++i)
    if (u(gen) > 0.6)
      for (int q = 0; q < np; ++q) m.sp_state[i * np + q] = kBroken;
  if (preload) {
    m.sp_g0.assign(m.n_springs(), 0.0);
    for (auto& g : m.sp_g0) g = 1e-6 * u(gen);
  }
  if (tied) {
    build_ties(m);
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      const bool cracked = m.sp_state[i * np] == kBroken;
      const bool opened = !cracked && u(gen) > 0.7;
      for (int q = 0; q < np; ++q)
        if (cracked || (opened && q == 0)) untie_point(m, i * np + q);
    }
  }
  // A random velocity field per mesh vertex plus a jitter per node that opens and slides the
  // spring points, graded along x from gentle (intact, some breaking: relative displacements of
  // ~1 um against tensile openings of ~2 um) to violent (separation beyond the release
  // distance within the run).
  double xmax = 0;
  for (const auto& p : m.vertex_X) xmax = std::max(xmax, p.x);
  std::vector<Vec3> vv(m.vertex_X.size());
  for (auto& v : vv) v = {u(gen), u(gen), three_d ? u(gen) : 0.0};
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    const Vec3 jitter{u(gen), u(gen), three_d ? u(gen) : 0.0};
    const double g = std::pow(m.X(n).x / xmax, 6);
    m.v[n] = 20.0 * g * (vv[m.node_vertex[n]] + jitter) + 4e-4 * jitter;
  }
  Counts c;  // intact after the first step, broken and released at the end
  const double dt = 4e-5;  // 60 steps: ~5 cm of relative motion, beyond the release distance for some
  Model ref = m, rank_a = m, rank_b = m;
  spring_forces_reference(m, dt, 0.0);  // first call: previous normals rebuilt (generic path)
  spring_forces_reference(ref, dt, 0.0);
  ranked_spring_step(rank_a, rank_b, dt, 0.0);
  for (int step = 1; step <= 60; ++step) {
    for (Model* mm : {&m, &ref, &rank_a, &rank_b})
      for (std::size_t n = 0; n < mm->n_nodes(); ++n) mm->x[n] += dt * mm->v[n];
    const std::vector<std::uint8_t> before = m.sp_state;
    spring_forces(m, dt, step * dt);
    for (std::size_t sp = 0; sp < m.sp_state.size(); ++sp) {
      if (before[sp] == kReleased || m.sp_state[sp] != kReleased) continue;
      const std::size_t i = sp / np;
      const double dist = m.release_distance_factor * 0.5 *
                          (m.block_size[m.iface_block_a[i]] + m.block_size[m.iface_block_b[i]]);
      c.by_angle += norm(m.x[m.sp_b[sp]] - m.x[m.sp_a[sp]]) <= dist;
    }
    spring_forces_reference(ref, dt, step * dt);
    ranked_spring_step(rank_a, rank_b, dt, step * dt);
    std::string differ = differing(m, ref);
    if (const std::string d = differing(rank_a, ref); !d.empty()) differ += " (rank a:" + d + ")";
    if (const std::string d = differing(rank_b, ref); !d.empty()) differ += " (rank b:" + d + ")";
    const bool same = differ.empty();
    EXPECT_TRUE(same) << (three_d ? "3D " : "2D ") << (tied ? "tied " : "") << name_of(law)
                      << (preload ? " preloaded" : "")
                      << ": after step " << step << " these differ:" << differ;
    if (!same) break;
    if (step == 1)
      for (auto st : m.sp_state) c.intact += st == kIntact;
  }
  for (auto st : m.sp_state) {
    c.broken += st == kBroken;
    c.released += st == kReleased;
  }
  return c;
}

TEST(SpringKernel, VectorisedMatchesReferenceBitForBit) {
  for (bool tied : {false, true})
  for (bool three_d : {true, false})
    for (InterfaceLaw law :
         {InterfaceLaw::Elastic, InterfaceLaw::MohrCoulomb, InterfaceLaw::FractureEnergy})
      for (bool preload : {false, true}) {
        const Counts c = run_pair(three_d, law, preload, tied);
        std::printf("[spring kernel] %s %-7s %-15s %-9s intact %zu (step 1), broken %zu, released %zu, "
                    "of them by the release angle %zu (end)\n",
                    three_d ? "3D" : "2D", tied ? "tied" : "springs", name_of(law), preload ? "preload" : "",
                    c.intact, c.broken, c.released, c.by_angle);
        // Every branch was taken: intact spring points after the first step, broken (in contact
        // or open) and released ones at the end (the elastic law's broken ones are the
        // pre-cracked).
        EXPECT_GT(c.intact, 0u);
        EXPECT_GT(c.broken, 0u);
        EXPECT_GT(c.released, 0u);
        EXPECT_GT(c.by_angle, 0u);  // the release by angle (broken_release) is taken too
      }
}

}  // namespace
}  // namespace cdem
