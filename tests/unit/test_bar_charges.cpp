// Unit tests of the bar explosion model (SPEC 2; explosive/charges.hpp): segmentation (eq. 8),
// binding to the crossed elements in 2D and 3D (along faces and edges too), the volume of
// eq. 9, ignition and energy release (eq. 12, 13), the attenuated pressure (eq. 14, 15), the
// inflating nodal forces (eq. 16), the input errors of build_bar_charges, and the hole / charge
// errors of load_case. Small models are built in code (tests/verification/charge_builders.hpp).
// Numbers: docs/verification_charges.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>

#include "cdem/core/error.hpp"
#include "cdem/explosive/charges.hpp"
#include "cdem/explosive/eos.hpp"
#include "cdem/io/case.hpp"
#include "verification/charge_builders.hpp"

namespace cdem {
namespace {

using namespace test_charges;

// Emulsion (SPEC 5.1): D = 5000 m/s, P0 = rho D^2 / (2 (gamma1 + 1)) = 1150 * 5000^2 / 8 Pa.
constexpr double kD = 5000.0;
constexpr double kP0 = 1150.0 * 5000.0 * 5000.0 / 8.0;

Model rock_model(const Mesh& mesh) {
  return build_model(mesh, {rock()}, {interface_of(InterfaceLaw::Elastic)}, "bar test model");
}

Case bar_case(const std::vector<HoleDef>& holes) {
  return charge_case({rock()}, {interface_of(InterfaceLaw::Elastic)}, holes);
}

std::set<std::int32_t> loaded_blocks(const BarCharges& bc) {
  return {bc.elem_block.begin(), bc.elem_block.end()};
}

// Structured grids: column i, row j of a uniform grid of cell h from the origin.
int column_of(Vec3 c, double h) { return static_cast<int>(std::floor(c.x / h)); }
int row_of(Vec3 c, double h) { return static_cast<int>(std::floor(c.y / h)); }

// Round-off tolerance of quantities computed by a handful of floating-point operations from
// inputs of order one: 1e-12 relative leaves three orders of margin over double precision.
constexpr double kRound = 1e-12;

// ---------------------------------------------------------------------------------------------
// Segmentation (eq. 8)
// ---------------------------------------------------------------------------------------------

// h = L / ceil(L / min L_c over the crossed elements): never longer than an element crossed, and
// as long as possible. The grid has two thin rows (cells 0.1 x 0.04, L_c = sqrt(0.004)).
TEST(BarSegmentation, LengthFromSmallestCrossedElement) {
  const Mesh mesh =
      graded_quad_grid({0, 0.1, 0.2, 0.3, 0.4}, {0, 0.1, 0.2, 0.24, 0.28, 0.38, 0.48});
  const Model m = rock_model(mesh);
  const Vec3 a0{0.15, 0.05, 0}, a1{0.15, 0.45, 0};  // crosses the thin rows
  const Vec3 b0{0.35, 0.02, 0}, b1{0.35, 0.17, 0};  // rows 0 and 1 only (L_c = 0.1)
  const Case c = bar_case({bar("thin", a0, a1, 0.02), bar("coarse", b0, b1, 0.02)});
  const BarCharges bc = build_bar_charges(m, charge_spec(c));
  ASSERT_EQ(bc.bars.size(), 2u);
  const std::vector<std::pair<Vec3, Vec3>> ends{{a0, a1}, {b0, b1}};
  const std::vector<int> expected_nseg{7, 2};  // ceil(0.4 / 0.0632) = 7, ceil(0.15 / 0.1) = 2
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& bar_k = bc.bars[k];
    // The crossed elements by the independent point-sampling reference; L_c = sqrt(area).
    const auto crossed = sampled_crossed_blocks(m, ends[k].first, ends[k].second, 4000);
    double lc_min = 1e300;
    for (auto b : crossed) lc_min = std::min(lc_min, std::sqrt(current_measure(m, b)));
    const double L = norm(ends[k].second - ends[k].first);
    const int nseg = static_cast<int>(std::ceil(L / lc_min));
    EXPECT_EQ(nseg, expected_nseg[k]);
    EXPECT_EQ(bar_k.seg_end - bar_k.seg_begin, nseg) << bar_k.hole;
    EXPECT_NEAR(bar_k.h, L / nseg, kRound * L) << bar_k.hole;
    for (auto b : crossed) EXPECT_LE(bar_k.h, std::sqrt(current_measure(m, b)) * (1 + kRound));
    // V0 = 2 r0 h per unit thickness in plane strain (the charge's cross-section is 2 r0 x 1 m).
    for (auto j = bar_k.seg_begin; j < bar_k.seg_end; ++j)
      EXPECT_NEAR(bc.seg_v0[j], 2.0 * 0.01 * bar_k.h, kRound * bc.seg_v0[j]);
  }
}

// L an exact multiple of the element size (0.6 m over cells of 0.1 m): 6 segments of 0.1 m, not
// 7 (the ceiling must not round 5.999...9 or 6.000...1 up).
TEST(BarSegmentation, ExactMultipleOfElementSize) {
  const Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  const BarCharges bc =
      build_bar_charges(m, charge_spec(bar_case({bar("full", {0.25, 0.0, 0}, {0.25, 0.6, 0}, 0.02)})));
  ASSERT_EQ(bc.bars.size(), 1u);
  EXPECT_EQ(bc.n_segments(), 6u);
  EXPECT_NEAR(bc.bars[0].h, 0.1, kRound);
}

// ---------------------------------------------------------------------------------------------
// Ignition (eq. 12) and energy release (eq. 13)
// ---------------------------------------------------------------------------------------------

// t_1 = t_D0 + d_j / D, d_j = (j + 1/2) h from the initiation point, for a bar initiated at its
// bottom, one initiated at its top, and a decked hole (two bars separated by stemming). Segment
// j's bound elements contain its centre start + d_j dir: the segments run from the initiation
// point.
TEST(BarIgnition, TimesFromInitiationPointBottomAndTop) {
  const Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  const HoleDef bottom = bar("bottom", {0.15, 0.05, 0}, {0.15, 0.55, 0}, 0.02, 1e-3, false);
  const HoleDef top = bar("top", {0.45, 0.05, 0}, {0.45, 0.55, 0}, 0.02, 2e-3, true);
  const HoleDef decked = make_hole("decked", {0.35, 0.6, 0}, {0.35, 0.0, 0}, 0.02,
                                   {{0.15, 0.0, false, 0.0}, {0.2, 5e-3, true, 0.1}});
  const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bottom, top, decked})));
  ASSERT_EQ(bc.bars.size(), 4u);
  struct Expect {
    std::string hole;
    int deck;
    Vec3 start, other;
    double t0;
  };
  const std::vector<Expect> ex{{"bottom", 0, {0.15, 0.05, 0}, {0.15, 0.55, 0}, 1e-3},
                               {"top", 0, {0.45, 0.55, 0}, {0.45, 0.05, 0}, 2e-3},
                               {"decked", 0, {0.35, 0.0, 0}, {0.35, 0.15, 0}, 0.0},
                               {"decked", 1, {0.35, 0.45, 0}, {0.35, 0.25, 0}, 5e-3}};
  for (std::size_t k = 0; k < ex.size(); ++k) {
    const auto& b = bc.bars[k];
    EXPECT_EQ(b.hole, ex[k].hole);
    EXPECT_EQ(b.deck, ex[k].deck);
    EXPECT_NEAR(norm(b.start - ex[k].start), 0.0, kRound);
    EXPECT_NEAR(b.length, norm(ex[k].other - ex[k].start), kRound);
    const Vec3 dir = normalized(ex[k].other - ex[k].start);
    for (auto j = b.seg_begin; j < b.seg_end; ++j) {
      const double dj = (j - b.seg_begin + 0.5) * b.h;
      // t ~ 1e-3 s: 1e-15 s absolute is a few ulps.
      EXPECT_NEAR(bc.seg_t_ign[j], ex[k].t0 + dj / kD, 1e-15)
          << b.hole << " deck " << b.deck << " seg " << j;
      const Vec3 centre = ex[k].start + dj * dir;
      bool contains = false;
      for (auto e : segment_blocks(bc, static_cast<std::size_t>(j)))
        contains = contains || point_in_block(m, e, centre, 1e-9);
      EXPECT_TRUE(contains) << b.hole << " seg " << j << ": no bound element contains its centre";
    }
    // Each deck binds exactly what its own segment of the hole crosses (not the stemming).
    EXPECT_EQ(bar_blocks(bc, k), sampled_crossed_blocks(m, ex[k].start, ex[k].other, 4000))
        << b.hole;
  }
}

// xi = clamp((t - t_1) D / h, 0, 1): read seg_xi after bar_loads at chosen times; P_r = xi P.
// No force at all before the first ignition.
TEST(BarIgnition, XiRampsLinearlyOverCrossingTime) {
  Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  BarCharges bc =
      build_bar_charges(m, charge_spec(bar_case({bar("ramp", {0.25, 0.05, 0}, {0.25, 0.55, 0}, 0.02, 1e-4)})));
  ASSERT_EQ(bc.n_segments(), 5u);
  const double h = bc.bars[0].h, p1 = eos_pressure(bc.eos[0], 1.0);
  EXPECT_NEAR(p1, kP0, kRound * kP0);
  {
    AppliedLoads out;
    bar_loads(m, bc, out, bc.seg_t_ign[0] - 1e-9);
    EXPECT_TRUE(out.node.empty()) << "forces before the first ignition";
    for (std::size_t j = 0; j < bc.n_segments(); ++j) EXPECT_EQ(bc.seg_p[j], 0.0);
  }
  for (std::size_t j = 0; j < bc.n_segments(); ++j)
    for (double frac : {-0.5, 0.0, 0.1, 0.25, 0.5, 0.75, 0.999, 1.0, 1.5, 10.0}) {
      AppliedLoads out;
      const double t = bc.seg_t_ign[j] + frac * h / kD;
      bar_loads(m, bc, out, t);
      const double xi = std::clamp(frac, 0.0, 1.0);
      // (t - t_1) D / h loses ~ulp(t) D / h = 2e-20 * 5000 / 0.1 ~ 1e-15 to round-off.
      EXPECT_NEAR(bc.seg_xi[j], xi, 1e-12) << "segment " << j << " at t_1 + " << frac << " h/D";
      EXPECT_NEAR(bc.seg_p[j], xi * kP0, 1e-12 * kP0);
      if (frac <= 0) {
        EXPECT_EQ(bc.seg_p[j], 0.0);
      }
    }
}

// ---------------------------------------------------------------------------------------------
// Nodal forces (eq. 16)
// ---------------------------------------------------------------------------------------------

// Sum of the forces bar_loads added to the nodes of each block, and the largest nodal force.
std::map<std::int32_t, std::pair<Vec3, double>> forces_by_block(const Model& m,
                                                                const AppliedLoads& out) {
  std::map<std::int32_t, std::pair<Vec3, double>> r;
  for (std::size_t i = 0; i < out.node.size(); ++i) {
    auto& e = r[m.node_block(out.node[i])];
    e.first += out.force[i];
    e.second = std::max(e.second, norm(out.force[i]));
  }
  return r;
}

// Every loaded element gets forces on all its nodes whose sum is zero to round-off (relative to
// one nodal force: sums of 3-4 terms of that size cancel to a few ulps; 1e-12 leaves margin).
// The mesh is randomly distorted first (current geometry), so the cancellation is not a symmetry.
void check_net_force_zero(Model& m, const Case& c) {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t n = 0; n < m.n_nodes(); ++n)
    for (int d = 0; d < m.dim; ++d) m.x[n][d] += 0.01 * u(gen) * m.block_size[m.node_block(n)];
  BarCharges bc = build_bar_charges(m, charge_spec(c));
  AppliedLoads out;
  bar_loads(m, bc, out, 1.0);  // long after ignition: xi = 1 everywhere
  const auto by_block = forces_by_block(m, out);
  EXPECT_EQ(by_block.size(), bc.elem_block.size());
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const auto b = bc.elem_block[i];
    ASSERT_TRUE(by_block.count(b)) << "loaded block " << b << " got no force";
    const auto& [sum, fmax] = by_block.at(b);
    EXPECT_GT(fmax, 0.0);
    EXPECT_LE(norm(sum), 1e-12 * fmax) << "block " << b;
    int nodes = 0;
    for (auto n : out.node) nodes += m.node_block(n) == b;
    EXPECT_EQ(nodes, nodes_of(m.block_type[b]));
  }
}

TEST(BarLoads, NetForceOnLoadedElementsIsZeroQuads) {
  Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  check_net_force_zero(m, bar_case({bar("q", {0.22, 0.05, 0}, {0.41, 0.55, 0}, 0.05)}));
}
TEST(BarLoads, NetForceOnLoadedElementsIsZeroTriangles) {
  Model m = rock_model(tri_grid(6, 6, 0.6, 0.6));
  check_net_force_zero(m, bar_case({bar("t", {0.22, 0.05, 0}, {0.41, 0.55, 0}, 0.05)}));
}
TEST(BarLoads, NetForceOnLoadedElementsIsZeroTets) {
  Model m = rock_model(tet_box(3, 3, 4, 0.3, 0.3, 0.4));
  check_net_force_zero(m, bar_case({bar("tet", {0.13, 0.16, 0.03}, {0.17, 0.12, 0.37}, 0.05)}));
}

// A lone square quad (side s) inflated by p: every node gets p (s/2)(n1 + n2), magnitude
// p s / sqrt(2), pointing away from the centroid along the diagonal; the sum is zero. Through
// bar_loads the pressure is sigma_b = P0 (r0 / L_c)^a (L_c = s, v = 1, xi = 1).
TEST(BarLoads, LoneSquareQuadInflatesSymmetrically) {
  const double s = 0.2;
  Model m =
      rock_model(single_element(ElemType::Quad4, {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}}));
  const Vec3 cen{0.5 * s, 0.5 * s, 0};
  auto check = [&](const AppliedLoads& out, double p) {
    ASSERT_EQ(out.node.size(), 4u);
    Vec3 sum{};
    for (std::size_t i = 0; i < 4; ++i) {
      const Vec3 f = out.force[i];
      sum += f;
      EXPECT_NEAR(norm(f), p * s / std::sqrt(2.0), kRound * p * s);
      // cosine of the angle between f and the outward diagonal = 1 to round-off
      EXPECT_NEAR(dot(f, normalized(m.x[out.node[i]] - cen)) / norm(f), 1.0, kRound);
    }
    EXPECT_LE(norm(sum), kRound * p * s);
  };
  {
    AppliedLoads out;
    inflate_block(m, 0, 1e6, out);
    check(out, 1e6);
  }
  // The bar runs down the middle over the full height: r0 / L_c = phi = 2 r0 / s.
  const double d = 0.08, att = std::pow(d / s, 1.25);
  BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("lone", {0.1, 0.0, 0}, {0.1, 0.2, 0}, d)})));
  ASSERT_EQ(bc.elem_block.size(), 1u);
  AppliedLoads out;
  bar_loads(m, bc, out, 1.0);
  // 1e-6: bound length measured against faces widened by 1e-6 L_c.
  EXPECT_NEAR(bc.elem_sigma[0], kP0 * att, 1e-6 * kP0 * att);
  check(out, bc.elem_sigma[0]);
}

// A lone regular tetrahedron (edge a) inflated by p: node i gets p / 3 times the sum of the area
// vectors of its three faces = -(p / 3) A_opposite, magnitude p (sqrt(3)/4 a^2) / 3, pointing
// away from the centroid; the sum is zero. The same through bar_loads with a bar along an
// altitude (from a vertex to the centre of the opposite face).
TEST(BarLoads, LoneRegularTetInflatesSymmetrically) {
  const double k = 0.05;  // vertices of a cube's alternate corners: edge a = 2 sqrt(2) k
  std::vector<Vec3> v{{k, k, k}, {k, -k, -k}, {-k, k, -k}, {-k, -k, k}};
  if (dot(v[1] - v[0], cross(v[2] - v[0], v[3] - v[0])) < 0) std::swap(v[1], v[2]);
  Model m = rock_model(single_element(ElemType::Tet4, v));
  const double a = 2.0 * std::sqrt(2.0) * k, face = std::sqrt(3.0) / 4.0 * a * a;
  auto check = [&](const AppliedLoads& out, double p) {
    ASSERT_EQ(out.node.size(), 4u);
    Vec3 sum{};
    for (std::size_t i = 0; i < 4; ++i) {
      const Vec3 f = out.force[i];
      sum += f;
      EXPECT_NEAR(norm(f), p * face / 3.0, kRound * p * face);
      EXPECT_NEAR(dot(f, normalized(m.x[out.node[i]])) / norm(f), 1.0, kRound);  // centroid 0
    }
    EXPECT_LE(norm(sum), kRound * p * face);
  };
  {
    AppliedLoads out;
    inflate_block(m, 0, 1e6, out);
    check(out, 1e6);
  }
  const Vec3 opp = (v[1] + v[2] + v[3]) / 3.0;
  // phi = pi r0^2 H / V (H the altitude the bar runs along), r0 / L_c = sqrt(phi) in 3D.
  const double d = 0.02, vol = std::abs(dot(v[1] - v[0], cross(v[2] - v[0], v[3] - v[0]))) / 6.0;
  const double phi = 3.14159265358979323846 * 0.01 * 0.01 * norm(v[0] - opp) / vol;
  BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("lone", opp, v[0], d)})));
  ASSERT_EQ(bc.elem_block.size(), 1u);
  EXPECT_NEAR(bc.seg_v0[0], 3.14159265358979323846 * 0.01 * 0.01 * bc.bars[0].h,
              kRound * bc.seg_v0[0]);
  AppliedLoads out;
  bar_loads(m, bc, out, 1.0);
  const double att = std::min(1.0, std::pow(std::sqrt(phi), 1.25));
  EXPECT_NEAR(bc.elem_phi[0], phi, 1e-6 * phi);
  EXPECT_NEAR(bc.elem_sigma[0], kP0 * att, 1e-6 * kP0 * att);
  check(out, bc.elem_sigma[0]);
}

// ---------------------------------------------------------------------------------------------
// Binding: exactly the crossed elements
// ---------------------------------------------------------------------------------------------

// A bar through the middle of a column of cells binds exactly that column (quads: one element
// per row; triangles: both triangles of every cell), over the rows it spans. Its ends (y = 0.02
// and 0.58) are off the cells' diagonals (crossed at y = 0.05 + 0.1 j), so that the end triangles
// are crossed over a positive length.
TEST(BarBinding, ThroughMiddleOfColumn2D) {
  for (bool tris : {false, true}) {
    const Model m = rock_model(tris ? tri_grid(6, 6, 0.6, 0.6) : quad_grid(6, 6, 0.6, 0.6));
    const BarCharges bc =
        build_bar_charges(m, charge_spec(bar_case({bar("mid", {0.25, 0.02, 0}, {0.25, 0.58, 0}, 0.02)})));
    const auto expected = blocks_where(m, [](Vec3 c) { return column_of(c, 0.1) == 2; });
    EXPECT_EQ(expected.size(), tris ? 12u : 6u);
    EXPECT_EQ(loaded_blocks(bc), expected) << (tris ? "triangles" : "quads");
    EXPECT_EQ(bar_blocks(bc, 0), expected);
  }
}

// A bar exactly along the edge x = 0.3 shared by columns 2 and 3 binds both columns (quads).
// Triangles: every triangle with an edge on that line (half of the two columns: the others only
// touch the line at a corner) is bound; that nothing more is bound is checked by
// NoBindingThroughPointContacts.
TEST(BarBinding, AlongSharedEdge2D) {
  for (bool tris : {false, true}) {
    const Model m = rock_model(tris ? tri_grid(6, 6, 0.6, 0.6) : quad_grid(6, 6, 0.6, 0.6));
    const Vec3 a{0.3, 0.05, 0}, b{0.3, 0.55, 0};
    const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("edge", a, b, 0.02)})));
    const auto ref = sampled_crossed_blocks(m, a, b, 4000);
    if (!tris) {
      const auto expected = blocks_where(m, [](Vec3 c) {
        const int i = column_of(c, 0.1);
        return i == 2 || i == 3;
      });
      EXPECT_EQ(ref, expected);
      EXPECT_EQ(loaded_blocks(bc), expected) << "quads";
    } else {
      EXPECT_EQ(ref.size(), 12u);
      const auto bound = loaded_blocks(bc);
      EXPECT_TRUE(std::includes(bound.begin(), bound.end(), ref.begin(), ref.end())) << "triangles";
    }
    // Every segment binds elements on both sides of the edge.
    for (std::size_t j = 0; j < bc.n_segments(); ++j) {
      int left = 0, right = 0;
      for (auto e : segment_blocks(bc, j)) (centroid0(m, e).x < 0.3 ? left : right)++;
      EXPECT_GT(left, 0) << "segment " << j;
      EXPECT_GT(right, 0) << "segment " << j;
    }
  }
}

// An inclined bar through a triangle grid: the bound set equals the independent point-sampling
// reference (elements the line crosses over a positive length).
TEST(BarBinding, InclinedBar2D) {
  const Model m = rock_model(tri_grid(6, 6, 0.6, 0.6));
  const Vec3 a{0.07, 0.04, 0}, b{0.52, 0.57, 0};
  const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("incl", a, b, 0.02)})));
  EXPECT_EQ(loaded_blocks(bc), sampled_crossed_blocks(m, a, b, 20000));
  // Segment by segment too.
  const auto& br = bc.bars[0];
  for (auto j = br.seg_begin; j < br.seg_end; ++j) {
    const Vec3 s0 = a + ((j - br.seg_begin) * br.h) * br.dir, s1 = s0 + br.h * br.dir;
    EXPECT_EQ(segment_blocks(bc, static_cast<std::size_t>(j)),
              sampled_crossed_blocks(m, s0, s1, 4000))
        << "segment " << j;
  }
}

// Tetrahedra (a box of 10 cm cubes, 6 Kuhn tets each). A bar in general position (vertical) and
// an oblique one: the bound set equals the point-sampling reference. A bar lying in a cube face
// (the plane x = 0.2, shared by the tets of two cells) binds every tet with a face on it, on both
// sides; a bar along a vertical cube edge binds every tet around the edge, in the four cells
// around it (that it binds nothing more: NoBindingThroughPointContacts). V0 = pi r0^2 h.
TEST(BarBinding, Tetrahedra3D) {
  const Model m = rock_model(tet_box(4, 4, 4, 0.4, 0.4, 0.4));
  struct Line {
    std::string name;
    Vec3 a, b;
    bool exact;  // general position: no point contacts
  };
  const std::vector<Line> lines{{"general", {0.13, 0.16, 0.05}, {0.13, 0.16, 0.35}, true},
                                {"oblique", {0.03, 0.07, 0.02}, {0.36, 0.31, 0.38}, true},
                                {"face", {0.2, 0.13, 0.05}, {0.2, 0.13, 0.35}, false},
                                {"edge", {0.2, 0.2, 0.05}, {0.2, 0.2, 0.35}, false}};
  for (const auto& l : lines) {
    const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar(l.name, l.a, l.b, 0.02)})));
    const auto ref = sampled_crossed_blocks(m, l.a, l.b, 6000);
    const auto bound = loaded_blocks(bc);
    if (l.exact)
      EXPECT_EQ(bound, ref) << l.name;
    else
      EXPECT_TRUE(std::includes(bound.begin(), bound.end(), ref.begin(), ref.end())) << l.name;
    for (std::size_t j = 0; j < bc.n_segments(); ++j)
      EXPECT_NEAR(bc.seg_v0[j], 3.14159265358979323846 * 1e-4 * bc.bars[0].h,
                  kRound * bc.seg_v0[j]);
    if (l.name == "face") {
      int left = 0, right = 0;
      for (auto e : ref) (centroid0(m, e).x < 0.2 ? left : right)++;
      EXPECT_GT(left, 0);
      EXPECT_GT(right, 0);
    }
    if (l.name == "edge") {
      std::set<std::pair<int, int>> cells;
      for (auto e : ref)
        cells.insert({column_of(centroid0(m, e), 0.1), row_of(centroid0(m, e), 0.1)});
      EXPECT_EQ(cells.size(), 4u) << "the cells around the edge";
    }
  }
}

// Elements that touch a bar (or a segment) only at isolated points must not be bound: here the
// bar and the segment ends lie on element edges, or the bar runs along an edge or a face and
// passes through vertices and across face diagonals. Each case against the point-sampling
// reference: (1) quads, a bar over rows 0.1 .. 0.4 (3 segments of exactly one cell): segment j
// binds row j + 1 of column 2 only; (2) triangles, a bar along x = 0.3 (the triangles of columns
// 2, 3 that only touch it at a corner); (3) tets, a bar in the face x = 0.2; (4) tets, a bar along
// a vertical cube edge.
TEST(BarBinding, NoBindingThroughPointContacts) {
  {
    const Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
    const BarCharges bc =
        build_bar_charges(m, charge_spec(bar_case({bar("ends", {0.25, 0.1, 0}, {0.25, 0.4, 0}, 0.02)})));
    EXPECT_EQ(loaded_blocks(bc), blocks_where(m, [](Vec3 c) {
                return column_of(c, 0.1) == 2 && row_of(c, 0.1) >= 1 && row_of(c, 0.1) <= 3;
              }));
    ASSERT_EQ(bc.n_segments(), 3u);
    for (std::size_t j = 0; j < 3; ++j) {
      const auto segj = segment_blocks(bc, j);
      ASSERT_EQ(segj.size(), 1u) << "segment " << j;
      EXPECT_EQ(row_of(centroid0(m, *segj.begin()), 0.1), static_cast<int>(j) + 1);
    }
  }
  {
    const Model m = rock_model(tri_grid(6, 6, 0.6, 0.6));
    const Vec3 a{0.3, 0.05, 0}, b{0.3, 0.55, 0};
    const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("edge", a, b, 0.02)})));
    EXPECT_EQ(loaded_blocks(bc), sampled_crossed_blocks(m, a, b, 4000))
        << "triangles along an edge";
  }
  const Model m = rock_model(tet_box(4, 4, 4, 0.4, 0.4, 0.4));
  for (const auto& [a, b] : {std::pair<Vec3, Vec3>{{0.2, 0.13, 0.05}, {0.2, 0.13, 0.35}},
                             std::pair<Vec3, Vec3>{{0.2, 0.2, 0.05}, {0.2, 0.2, 0.35}}}) {
    const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("tets", a, b, 0.02)})));
    EXPECT_EQ(loaded_blocks(bc), sampled_crossed_blocks(m, a, b, 6000))
        << "tets at x = " << a.x << ", y = " << a.y;
  }
}

// A bar passing very close to mesh vertices (a diagonal of a 0.1 m grid, shifted by e = 0 ..
// 1e-4 m, i.e. 0 .. 1e-3 L_c) lies inside the mesh over its whole length: no "void" error, and
// the cells it runs through along their diagonal are bound (quads: the 6 diagonal cells, crossed
// over 0.07 .. 0.14 m; the cells whose corners it clips may or may not be, by the length
// clipped). Triangles (cell diagonals along the bar): the upper triangles of those cells.
TEST(BarBinding, BarCloseToVerticesIsNotAVoid) {
  for (bool tris : {false, true}) {
    const Model m = rock_model(tris ? tri_grid(6, 6, 0.6, 0.6) : quad_grid(6, 6, 0.6, 0.6));
    for (double e : {0.0, 1e-7, 1e-6, 3e-6, 1e-5, 1e-4}) {
      BarCharges bc;
      ASSERT_NO_THROW(bc = build_bar_charges(m, charge_spec(bar_case({bar("near_vertex", {0.05, 0.05 + e, 0},
                                                              {0.55, 0.55 + e, 0}, 0.02)}))))
          << (tris ? "triangles" : "quads") << ", e = " << e;
      const auto bound = loaded_blocks(bc);
      const auto diagonal = blocks_where(m, [&](Vec3 c) {
        const int i = column_of(c, 0.1), j = row_of(c, 0.1);
        return i == j && (!tris || c.y > c.x);  // triangles: the upper one of the cell
      });
      EXPECT_TRUE(std::includes(bound.begin(), bound.end(), diagonal.begin(), diagonal.end()))
          << (tris ? "triangles" : "quads") << ", e = " << e;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Volume (eq. 9), pressure (eq. 10, 11, 14) and attenuation (eq. 15)
// ---------------------------------------------------------------------------------------------

// V / V0 = 1 + mean (J - 1) over the segment's bound elements; P = EOS(V / V0); P_bar of an
// element = mean P_r of its segments; sigma_b = P_bar (r0 / L_c)^a. The bar runs along the edge
// x = 0.3 from y = 0.05 to 0.55: 5 segments of 0.1 m, segment j binds rows j and j + 1 of columns
// 2 and 3 (4 elements), each element is bound to 1 or 2 segments. J is set by hand per block,
// from compressed (0.9) to past the Landau stage change (vc ~ 2.3).
TEST(BarVolume, FollowsBoundElementsVolumeRatio) {
  Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  // The bar runs along the edge between columns 2 and 3: over each stretch the two cells host
  // the 0.1 m wide charge together (0.2 m of host width), phi = 0.5 and r0 / L_c = phi in plane
  // strain. The end rows 0 and 5 hold it over half their height only: phi = 0.25.
  const double d = 0.1;
  auto att_of_row = [](int r) { return std::pow(r == 0 || r == 5 ? 0.25 : 0.5, 1.25); };
  BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("vol", {0.3, 0.05, 0}, {0.3, 0.55, 0}, d)})));
  ASSERT_EQ(bc.n_segments(), 5u);
  std::map<std::int32_t, double> jv;
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    const Vec3 c = centroid0(m, static_cast<std::int32_t>(b));
    m.vol_ratio[b] = 0.9 + 0.5 * row_of(c, 0.1) + (column_of(c, 0.1) == 2 ? 0.0 : 0.04);
    jv[static_cast<std::int32_t>(b)] = m.vol_ratio[b];
  }
  AppliedLoads out;
  bar_loads(m, bc, out, 1.0);
  const auto& eos = bc.eos[0];
  std::vector<double> p_expected(5);
  for (int j = 0; j < 5; ++j) {
    const auto expected = blocks_where(m, [j](Vec3 c) {
      const int i = column_of(c, 0.1), r = row_of(c, 0.1);
      return (i == 2 || i == 3) && (r == j || r == j + 1);
    });
    EXPECT_EQ(segment_blocks(bc, static_cast<std::size_t>(j)), expected) << "segment " << j;
    double theta = 0;
    for (auto b : expected) theta += jv[b] - 1.0;
    const double v = 1.0 + theta / static_cast<double>(expected.size());
    EXPECT_NEAR(bc.seg_v[j], v, kRound * v) << "segment " << j;
    p_expected[j] = eos_pressure(eos, v);
    EXPECT_NEAR(bc.seg_p[j], p_expected[j], kRound * p_expected[j]) << "segment " << j;
  }
  // Independent of eos_pressure: the first Landau stage P0 v^-gamma1 for segments 0 and 1
  // (v = 1.17 and 1.67, below vc), and pressures that fall as the charge expands.
  const double vc = std::get<LandauEos>(eos).vc;
  EXPECT_GT(vc, 2.0);
  for (int j = 0; j < 2; ++j)
    EXPECT_NEAR(bc.seg_p[j], kP0 * std::pow(bc.seg_v[j], -3.0), 1e-12 * kP0);
  EXPECT_GT(bc.seg_v[4], vc);  // second stage
  for (int j = 1; j < 5; ++j) EXPECT_LT(bc.seg_p[j], bc.seg_p[j - 1]);
  // Per element: the mean of its segments' P_r, times the attenuation.
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const int r = row_of(centroid0(m, bc.elem_block[i]), 0.1);
    double pbar = 0;
    int n = 0;
    for (int j : {r - 1, r})
      if (j >= 0 && j < 5) pbar += p_expected[j], ++n;
    pbar /= n;
    const double att = att_of_row(r);
    // 1e-6: the bar's bound length in each cell is measured against faces widened by
    // 1e-6 L_c (so that a bar along a face binds both sides), which shifts phi by ~1e-6.
    EXPECT_NEAR(bc.elem_atten[i], att, 1e-6 * att) << "row " << r;
    EXPECT_NEAR(bc.elem_sigma[i], pbar * bc.elem_atten[i], kRound * pbar) << "row " << r;
  }
}

// min(1, (r0 / L_c)^a) for several exponents and radii (L_c = 0.1 m), capped at 1 for a charge
// wider than the element; sigma_b = P0 x that factor when v = 1 and xi = 1.
// sigma_b = P_bar min(1, (r0 / L_c)^a) with L_c the element's equivalent radius about the bar
// (the half-width of the strip with the element's area and the bar's length in it, in plane
// strain): here each bar runs down the middle of a column of 0.1 m cells over their whole
// height, so r0 / L_c = 2 r0 / 0.1 = the charge's area fraction phi = d / 0.1.
TEST(BarAttenuation, FactorAndCap) {
  Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  struct Hole {
    double x, d, a, expected;
  };
  const std::vector<Hole> hs{{0.05, 0.02, 1.25, std::pow(0.2, 1.25)},
                             {0.15, 0.02, 2.0, 0.04},
                             {0.25, 0.02, 0.0, 1.0},
                             {0.35, 0.06, 1.25, std::pow(0.6, 1.25)},
                             {0.45, 0.3, 1.25, 1.0}};  // phi = 3: (3)^1.25 without the cap
  std::vector<HoleDef> holes;
  for (std::size_t k = 0; k < hs.size(); ++k) {
    std::string name = "h";  // (not "h" + to_string: a GCC 12 -Wrestrict false positive)
    name += std::to_string(k);
    holes.push_back(
        bar(name, {hs[k].x, 0.0, 0}, {hs[k].x, 0.6, 0}, hs[k].d, 0.0, false, hs[k].a));
  }
  BarCharges bc = build_bar_charges(m, charge_spec(bar_case(holes)));
  AppliedLoads out;
  bar_loads(m, bc, out, 1.0);
  ASSERT_EQ(bc.elem_block.size(), 30u);
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    const int col = column_of(centroid0(m, bc.elem_block[i]), 0.1);
    ASSERT_LT(col, 5);
    // 1e-6: the faces are widened by 1e-6 L_c when the bar is clipped (see BarVolume).
    EXPECT_NEAR(bc.elem_phi[i], hs[col].d / 0.1, 1e-6) << "hole " << col;
    EXPECT_NEAR(bc.elem_atten[i], hs[col].expected, 1e-6) << "hole " << col;
    EXPECT_NEAR(bc.elem_sigma[i], kP0 * bc.elem_atten[i], kRound * kP0) << "hole " << col;
  }
}

// attenuation_length = "element_size" (SPEC 2 read literally): L_c is the block's size (0.1 m
// cells: L_c = 0.1), so a 0.02 m charge is attenuated by (0.01 / 0.1)^1.25, not (0.2)^1.25.
TEST(BarAttenuation, ElementSizeOption) {
  Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  HoleDef h = bar("lit", {0.05, 0.0, 0}, {0.05, 0.6, 0}, 0.02);
  h.lc_element_size = true;
  BarCharges bc = build_bar_charges(m, charge_spec(bar_case({h})));
  ASSERT_EQ(bc.elem_block.size(), 6u);
  for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
    EXPECT_NEAR(bc.elem_atten[i], std::pow(0.1, 1.25), kRound);
    EXPECT_NEAR(bc.elem_phi[i], 0.2, 1e-6);  // the charge share is the same either way
  }
}

// The charge volume is shared out, never lost or counted twice: the bound tets' charge
// volumes sum to pi r0^2 L, for a bar through the tets' interiors and for one along an edge
// shared by several tets. In 3D r0 / L_c = sqrt(phi).
TEST(BarCharge, VolumeSharedAmongBoundTets) {
  const Model m = rock_model(tet_box(4, 4, 4, 0.4, 0.4, 0.4));
  const double r0 = 0.01;
  for (const auto& ends : std::vector<std::pair<Vec3, Vec3>>{
           {{0.1234, 0.1567, 0.0}, {0.2345, 0.1789, 0.4}},   // oblique, through interiors
           {{0.2, 0.2, 0.0}, {0.2, 0.2, 0.4}}}) {            // along cell edges
    const BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("b", ends.first, ends.second, 2 * r0)})));
    double sum = 0;
    for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
      sum += bc.elem_phi[i] * m.block_volume0[bc.elem_block[i]];
      EXPECT_NEAR(bc.elem_atten[i], std::pow(std::sqrt(bc.elem_phi[i]), 1.25), kRound);
    }
    const double L = norm(ends.second - ends.first);
    // 1e-5: bound lengths measured against faces widened by 1e-6 L_c, on each of a few dozen tets.
    EXPECT_NEAR(sum, 3.14159265358979323846 * r0 * r0 * L, 1e-5 * sum);
  }
}

// Blocks that are mostly charge (phi >= 0.5) are glued to their neighbours like explosive
// blocks: every interface of theirs gets the unbreakable elastic "charge_contact" law, and only
// those; they count as charge (no rock volume) in fragments, grading and funnel. Blocks that
// are mostly rock keep their interfaces and a rock volume fraction 1 - phi.
TEST(BarCharge, MostlyChargeBlocksGlued) {
  struct Variant {
    double d, phi;
    bool glued;
  };
  for (const auto& v : std::vector<Variant>{{0.15, 1.5, true}, {0.055, 0.55, true}, {0.045, 0.45, false}}) {
    Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
    const Model ref = m;
    BarCharges bc = build_bar_charges(m, charge_spec(bar_case({bar("c", {0.25, 0.0, 0}, {0.25, 0.6, 0}, v.d)})));
    make_charge_cavities(m, bc);
    std::set<std::int32_t> bound;
    for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
      const auto& mat = m.block_materials[m.block_material[bc.elem_block[i]]];
      EXPECT_NEAR(bc.elem_phi[i], v.phi, 1e-6);
      EXPECT_EQ(mat.charge_block, v.glued) << "d = " << v.d;
      EXPECT_NEAR(mat.rock_fraction(), v.glued ? 0.0 : 1.0 - v.phi, 1e-6);
      EXPECT_NEAR(mat.youngs, ref.block_materials[0].youngs * (1 - std::min(1.0, v.phi)),
                  1e-6 * ref.block_materials[0].youngs);
      bound.insert(bc.elem_block[i]);
    }
    ASSERT_EQ(bound.size(), 6u);
    std::size_t glued = 0;
    for (std::size_t f = 0; f < m.n_ifaces(); ++f) {
      const bool touches = bound.count(m.iface_block_a[f]) || bound.count(m.iface_block_b[f]);
      if (touches && v.glued) {
        ++glued;
        EXPECT_EQ(m.iface_materials[m.iface_material[f]].name, "charge_contact");
        EXPECT_EQ(m.spring_laws[m.iface_material[f]].law, InterfaceLaw::Elastic);
      } else {
        EXPECT_EQ(m.iface_material[f], ref.iface_material[f]);
      }
    }
    EXPECT_EQ(glued, v.glued ? 5u + 2u * 6u : 0u);  // 5 between the column's cells, 6 each side
  }
}

// make_charge_cavities: a bound block's Lame constants are scaled by its rock fraction 1 - phi,
// its density mixed by volume, its nodes' masses follow; cavity = false leaves the rock as it
// is. The time-step bound includes the products' tangent stiffness gamma1 P0 (Landau).
TEST(BarCharge, CavityMaterialFromChargeShare) {
  for (const bool cavity : {true, false}) {
    Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
    const Model ref = m;
    HoleDef h = bar("c", {0.25, 0.0, 0}, {0.25, 0.6, 0}, 0.06);  // phi = 0.6 in its column
    h.cavity = cavity;
    BarCharges bc = build_bar_charges(m, charge_spec(bar_case({h})));
    const double dt = make_charge_cavities(m, bc);
    ASSERT_EQ(bc.elem_block.size(), 6u);
    const double phi = 0.6, lam = ref.mat_lambda[0], G = ref.mat_shear[0];
    const double rho = ref.block_materials[0].density;
    const double rho_c = cavity ? (1 - phi) * rho + phi * 1150.0 : rho;
    double dt_expected = 1e300;
    for (std::size_t i = 0; i < bc.elem_block.size(); ++i) {
      const auto b = bc.elem_block[i];
      const auto k = m.block_material[b];
      EXPECT_NEAR(m.mat_lambda[k], cavity ? (1 - phi) * lam : lam, 1e-6 * lam);
      EXPECT_NEAR(m.mat_shear[k], cavity ? (1 - phi) * G : G, 1e-6 * G);
      EXPECT_NEAR(m.block_materials[k].density, rho_c, 1e-6 * rho);
      EXPECT_EQ(bc.elem_cavity[i], cavity ? 1 : 0);
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
        EXPECT_NEAR(m.mass[n], ref.mass[n] * rho_c / rho, 1e-6 * ref.mass[n]);
        EXPECT_DOUBLE_EQ(m.inv_mass[n], 1.0 / m.mass[n]);
      }
      const double lc = m.mat_lambda[k], gc = m.mat_shear[k];
      // gamma1 P0 = 3 P0: -dP/dv of P0 v^-3 at v = 1 (the central difference is within 3e-8).
      const double c = std::sqrt((lc + 2 * gc + bc.elem_atten[i] * 3.0 * kP0) / rho_c);
      dt_expected = std::min(dt_expected, m.block_altitude0[b] / c);
    }
    EXPECT_NEAR(dt, dt_expected, 1e-6 * dt_expected);
    // Blocks not bound keep their material and masses.
    std::size_t changed = 0;
    for (std::size_t b = 0; b < m.n_blocks(); ++b) changed += m.block_material[b] != ref.block_material[b];
    EXPECT_EQ(changed, cavity ? 6u : 0u);
  }
}

// ---------------------------------------------------------------------------------------------
// Input errors of build_bar_charges
// ---------------------------------------------------------------------------------------------

// The InputError message of f(), or "" when nothing is thrown.
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BarErrors, BarPartlyOutsideMesh) {
  const Model m = rock_model(quad_grid(6, 6, 0.6, 0.6));
  const std::string msg = input_error([&] {
    build_bar_charges(m, charge_spec(bar_case({bar("poking_out", {0.25, 0.3, 0}, {0.25, 0.8, 0}, 0.02)})));
  });
  ASSERT_FALSE(msg.empty()) << "no InputError for a bar leaving the mesh";
  EXPECT_NE(msg.find("hole 'poking_out'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("leaves the mesh"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.3 m from its initiation point"), std::string::npos)
      << msg;  // leaves at y = 0.6
}

TEST(BarErrors, BarCrossingVoid) {
  Mesh mesh = quad_grid(6, 6, 0.6, 0.6);
  // A void 0.1 m high across columns 1..3: a hole region with no elements.
  remove_elements(mesh, [](Vec3 c) { return c.y > 0.3 && c.y < 0.4 && c.x > 0.1 && c.x < 0.4; });
  const Model m = rock_model(mesh);
  const std::string msg = input_error([&] {
    build_bar_charges(m, charge_spec(bar_case({bar("across_void", {0.25, 0.05, 0}, {0.25, 0.55, 0}, 0.02)})));
  });
  ASSERT_FALSE(msg.empty()) << "no InputError for a bar crossing a void";
  EXPECT_NE(msg.find("hole 'across_void'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("crosses a void"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.25 m from its initiation point"), std::string::npos)
      << msg;  // void at y = 0.3
  // The same bar beside the void is fine.
  EXPECT_NO_THROW(
      build_bar_charges(m, charge_spec(bar_case({bar("beside", {0.45, 0.05, 0}, {0.45, 0.55, 0}, 0.02)}))));
}

TEST(BarErrors, BarThroughExplosiveBlocksRefused) {
  Mesh mesh = quad_grid(6, 6, 0.6, 0.6);
  assign_region(mesh, "charge", [](Vec3 c) { return c.x > 0.2 && c.x < 0.3 && c.y > 0.3; });
  BlockMaterial ex;
  ex.name = "emulsion_charge";
  ex.regions = {"charge"};
  ex.explosive = "emulsion";
  ex.density = 1150;
  ex.youngs = 1e9;
  ex.poisson = 0.25;
  const Model m = build_model(mesh, {rock(), ex}, {interface_of(InterfaceLaw::Elastic)}, "test");
  const Case c = charge_case({rock(), ex}, {interface_of(InterfaceLaw::Elastic)},
                             {bar("in_charge", {0.25, 0.05, 0}, {0.25, 0.55, 0}, 0.02)});
  const std::string msg = input_error([&] { build_bar_charges(m, charge_spec(c)); });
  ASSERT_FALSE(msg.empty()) << "a bar through explosive blocks was accepted";
  EXPECT_NE(msg.find("hole 'in_charge'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("explosive blocks"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'charge'"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------------------------
// Case-file errors for holes (load_case)
// ---------------------------------------------------------------------------------------------

const char* kCaseHead = R"(title = "holes"
[mesh.generate]
shape = "rectangle"
origin = [0.0, 0.0]
size = [1.0, 1.0]
element_size = 0.1
[simulation]
end_time = 1e-4
[[material]]
name = "rock"
regions = ["rock"]
density = 2500
youngs_modulus = 10e9
poisson_ratio = 0.25
[[interface]]
name = "bond"
default = true
law = "elastic"
)";

// Hole 'h1', 0.5 m deep: stemming 0.1, deck 0.2 (delay 1 ms), stemming 0.1, deck 0.1 (top).
const char* kHole = R"([[hole]]
name = "h1"
collar = [0.5, 1.0]
end = [0.5, 0.5]
diameter = 0.05
[[hole.charge]]
stemming = 0.1
[[hole.charge]]
explosive = "emulsion"
length = 0.2
delay = 1e-3
[[hole.charge]]
stemming = 0.1
[[hole.charge]]
explosive = "emulsion"
length = 0.1
initiation = "top"
)";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  if (p != std::string::npos) s.replace(p, from.size(), to);
  return s;
}

TEST(HoleCaseFile, ValidHoleDecksPlacedFromBottom) {
  TempDir dir("holes");
  const Case c = load_case(dir.write("ok.toml", std::string(kCaseHead) + kHole));
  ASSERT_EQ(c.holes.size(), 1u);
  const auto& h = c.holes[0];
  EXPECT_EQ(h.model, ChargeModel::Bar);
  EXPECT_DOUBLE_EQ(h.attenuation_exponent, 1.25);
  ASSERT_EQ(h.decks.size(), 2u);
  EXPECT_NEAR(h.decks[0].bottom.y, 0.6, kRound);
  EXPECT_NEAR(h.decks[0].top.y, 0.8, kRound);
  EXPECT_DOUBLE_EQ(h.decks[0].delay, 1e-3);
  EXPECT_FALSE(h.decks[0].initiate_top);
  EXPECT_NEAR(h.decks[1].bottom.y, 0.9, kRound);
  EXPECT_NEAR(h.decks[1].top.y, 1.0, kRound);
  EXPECT_TRUE(h.decks[1].initiate_top);
  EXPECT_NEAR(h.decks[1].initiation().y, 1.0, kRound);
  ASSERT_NE(c.explosive("emulsion"), nullptr);
  // 'direction' and 'depth' instead of 'end'.
  const Case c2 = load_case(dir.write(
      "dir.toml", std::string(kCaseHead) +
                      replaced(kHole, "end = [0.5, 0.5]", "direction = [0.0, -2.0]\ndepth = 0.5")));
  EXPECT_NEAR(norm(c2.holes[0].end - Vec3{0.5, 0.5, 0}), 0.0, kRound);
}

// Each malformed hole gives an InputError that names the file and says what is wrong.
TEST(HoleCaseFile, Errors) {
  TempDir dir("holes");
  struct Bad {
    std::string name, text, expect1, expect2;
  };
  const std::string head = kCaseHead, hole = kHole;
  const std::vector<Bad> bad{
      {"too_long", head + replaced(hole, "length = 0.2", "length = 0.35"), "longer than the hole",
       "hole 'h1'"},
      {"unknown_explosive",
       head + replaced(hole, "explosive = \"emulsion\"", "explosive = \"nitro_x\""),
       "unknown explosive 'nitro_x'", "emulsion"},
      {"no_charge", head + hole.substr(0, hole.find("[[hole.charge]]")), "has no charge",
       "hole 'h1'"},
      {"end_and_depth",
       head + replaced(hole, "end = [0.5, 0.5]",
                       "end = [0.5, 0.5]\ndirection = [0.0, -1.0]\ndepth = 0.5"),
       "either 'end'", "'depth'"},
  };
  for (const auto& b : bad) {
    const std::string path = dir.write(b.name + ".toml", b.text);
    const std::string msg = input_error([&] { load_case(path); });
    ASSERT_FALSE(msg.empty()) << b.name << ": accepted";
    EXPECT_NE(msg.find(b.name + ".toml"), std::string::npos) << b.name << ": " << msg;
    EXPECT_NE(msg.find(b.expect1), std::string::npos) << b.name << ": " << msg;
    EXPECT_NE(msg.find(b.expect2), std::string::npos) << b.name << ": " << msg;
  }
}

}  // namespace
}  // namespace cdem
