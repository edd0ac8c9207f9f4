// The edge contacts' geometry and tests (physics/contact_edge_geometry.hpp): a tetrahedron's
// geometry this step, the separating-plane test of two, the edge-pair test and its vector
// prefilter. The passes over the block pairs that use them are in contact_edges.cpp (whose
// header comment gives the contact law). Compiled without contraction, as contact.cpp, whose
// face planes tet_geom takes over bit for bit (CMakeLists.txt).
#include "cdem/physics/contact_edge_geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "cdem/mesh/element_geometry.hpp"

namespace cdem {
namespace {

// A tetrahedron's nodes, velocities, bounding radius (about the centroid in g.c) and edges.
void tet_nodes_and_edges(const Vec3* x, const Vec3* v, TetGeom& g) {
  for (int i = 0; i < 4; ++i) {
    g.x[i] = x[i];
    g.v[i] = v[i];
  }
  double r2 = 0;
  for (int i = 0; i < 4; ++i) r2 = std::max(r2, dot(g.x[i] - g.c, g.x[i] - g.c));
  g.r = std::sqrt(r2);
  for (int e = 0; e < 6; ++e) {
    const Vec3 p0 = g.x[kTetEdges[e][0]], p1 = g.x[kTetEdges[e][1]];
    g.em[e] = 0.5 * (p0 + p1);
    g.el[e] = norm(p1 - p0);
  }
}

}  // namespace

void tet_geom_of(const Vec3* x, const Vec3* v, double block_size, TetGeom& g) {
  g.c = Vec3{};
  for (int i = 0; i < 4; ++i) g.c += x[i];
  g.c *= 0.25;
  g.tol = 1e-3 * block_size;
  const LocalFaces lf = local_faces(ElemType::Tet4);
  for (int k = 0; k < 4; ++k) {
    const Vec3 a0 = x[lf.f[k][0]];
    g.a0[k] = a0;
    g.n[k] = normalized(cross(x[lf.f[k][1]] - a0, x[lf.f[k][2]] - a0));
  }
  g.rho = simplex_tolerance_reach(ElemType::Tet4, x, g.a0, g.n, g.tol);
  tet_nodes_and_edges(x, v, g);
  g.cand_edges = 63;
}

// Block b's geometry; its centroid, tolerance and face planes are those of the node pairs' step
// (contact.cpp, cb_geom) when it is one of their blocks (slot >= 0): the same expressions on the
// same positions (both files without contraction), so the same bits, computed once.
void tet_geom(const Model& m, const ContactSet& cs, std::int32_t b, TetGeom& g) {
  const std::int32_t n0 = m.block_first_node[b], slot = cs.block_slot[b];
  if (slot >= 0) {
    const BlockPlanes& bp = cs.cb_geom[static_cast<std::size_t>(slot)];
    g.c = bp.c;
    g.tol = bp.tol;
    g.a0 = bp.a0;
    g.n = bp.n;
    g.rho = bp.rho;
    tet_nodes_and_edges(&m.x[n0], &m.v[n0], g);
  } else {
    tet_geom_of(&m.x[n0], &m.v[n0], m.block_size[b], g);
  }
  g.cand_edges = 0;
  for (int e = 0; e < 6; ++e)
    if (cs.face_cand[4 * b + kTetEdgeFaces[e][0]] || cs.face_cand[4 * b + kTetEdgeFaces[e][1]])
      g.cand_edges |= 1 << e;
}

namespace {

// Per set of a tetrahedron's nodes (4 bits), the edges with both ends in it (6 bits).
constexpr std::array<int, 16> kEdgesWithin = [] {
  std::array<int, 16> t{};
  for (int set = 0; set < 16; ++set)
    for (int e = 0; e < 6; ++e)
      if ((set >> kTetEdges[e][0] & 1) && (set >> kTetEdges[e][1] & 1)) t[set] |= 1 << e;
  return t;
}();

}  // namespace

// Is every node of S in front of one face plane of G (beyond tol)? Then the two tetrahedra
// do not overlap and no edge of either is inside the other. (Touching blocks, within tol of a
// common plane, are not separated: their coplanar edge crossings hold aligned blocks whose
// vertex contacts alone let a corner node slip in; see docs/verification_contact.md.)
// Otherwise `edges` gets the edges of S that may have a point inside G: an edge both of whose
// ends are in front of one face plane of G by more than 2 tol has none (every point of it is in
// front of that plane by more than 2 tol, less rounding, so `inside` rejects it and no edge pair
// with it can hit: skipping it changes no result).
// When separated, `gap` gets how far S's nodes are in front of that plane (the least of them).
bool separated(const TetGeom& G, const TetGeom& S, int& edges, double& gap) {
  // The 16 signed distances first, S's nodes by coordinate so that the four of a face plane are
  // one vector operation, and then the tests on them as bit masks: the same products and sums as
  // dot(S.x[i] - G.a0[k], G.n[k]) (this file is compiled without contraction), so the same bits,
  // without the data-dependent branches of testing one distance at a time.
  double sx[4], sy[4], sz[4];
  for (int i = 0; i < 4; ++i) sx[i] = S.x[i].x, sy[i] = S.x[i].y, sz[i] = S.x[i].z;
  int front1 = 0, front2 = 0;  // bit 4 k + i: node i of S in front of face k of G by more than tol, 2 tol
  double dist[4][4];
  const double tol = G.tol, tol2 = 2 * G.tol;
  for (int k = 0; k < 4; ++k) {
    const Vec3 a0 = G.a0[k], n = G.n[k];
    int m1 = 0, m2 = 0;
    for (int i = 0; i < 4; ++i) {
      const double g = (sx[i] - a0.x) * n.x + (sy[i] - a0.y) * n.y + (sz[i] - a0.z) * n.z;
      dist[k][i] = g;
      m1 |= (g > tol) << i;
      m2 |= (g > tol2) << i;
    }
    front1 |= m1 << (4 * k);
    front2 |= m2 << (4 * k);
  }
  for (int k = 0; k < 4; ++k)
    if (((front1 >> (4 * k)) & 15) == 15) {
      double least = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 4; ++i) least = std::min(least, dist[k][i]);
      gap = least;
      return true;
    }
  // an edge is out when both its ends are in front of one plane: per plane, the edges whose two
  // nodes are in its 4-bit set (kEdgesWithin)
  int out = 0;
  for (int k = 0; k < 4; ++k) out |= kEdgesWithin[(front2 >> (4 * k)) & 15];
  edges = ~out & 63;
  return false;
}

namespace {

bool inside(const TetGeom& g, const Vec3& p) {
  for (int k = 0; k < 4; ++k)
    if (dot(p - g.a0[k], g.n[k]) > g.tol) return false;
  return true;
}

}  // namespace

// Edge ea of A against edge eb of B. A role "P's edge into Q": the two edges' bounding spheres
// meet (each edge's midpoint and length from its block's geometry); the lines are not nearly
// parallel (the vertices' contacts hold those); their closest points lie inside both segments;
// the common normal, turned out of Q (along the sum of Q's two outward face normals at its
// edge), points against the sum of P's (P's edge faces into Q there); P's point is inside Q, Q's inside P, and the
// depth along the normal is positive. A's edge into B is tried first, then B's into A.
// The second role's quantities are the first's with A and B swapped, and IEEE arithmetic gives
// them exactly (x - y = -(y - x); products commute; the same sums in the same order): r' = -r,
// c' = -f, f' = -c, den' = den, s' = t, t' = s, n' = -n before it is turned, pa' = pb, pb' = pa.
// So the lines' closest points are computed once, for both. Only the sphere reach and the
// parallel threshold are summed in another order, so each role has its own: the results are
// bit for bit those of testing the two roles one after the other (as before 4 Dec 2026).
// Returns 0 (no contact), 1 (A's edge pushed along +n) or 2 (B's).
int edge_hit_either(const TetGeom& A, int ea, const TetGeom& B, int eb, EdgeHit& h) {
  const Vec3 p0 = A.x[kTetEdges[ea][0]], p1 = A.x[kTetEdges[ea][1]];
  const Vec3 q0 = B.x[kTetEdges[eb][0]], q1 = B.x[kTetEdges[eb][1]];
  const Vec3 dm = A.em[ea] - B.em[eb];
  const double dm2 = dot(dm, dm);
  const double reach_ab = 0.5 * (A.el[ea] + B.el[eb]) + A.tol + B.tol;
  const double reach_ba = 0.5 * (B.el[eb] + A.el[ea]) + B.tol + A.tol;
  const bool near_ab = !(dm2 > reach_ab * reach_ab), near_ba = !(dm2 > reach_ba * reach_ba);
  if (!near_ab && !near_ba) return 0;
  const Vec3 da = p1 - p0, db = q1 - q0;
  const Vec3 r = p0 - q0;
  const double a = dot(da, da), e = dot(db, db), b = dot(da, db), c = dot(da, r), f = dot(db, r);
  const double den = a * e - b * b;
  const bool ok_ab = near_ab && den > 1e-6 * a * e;  // (not nearly parallel)
  const bool ok_ba = near_ba && den > 1e-6 * e * a;
  if (!ok_ab && !ok_ba) return 0;
  const double s = (b * f - c * e) / den, t = (a * f - b * c) / den;
  if (!(s > 0.01 && s < 0.99 && t > 0.01 && t < 0.99)) return 0;
  // Either role needs A's point inside B and B's inside A: tested first, it rejects about nine
  // in ten of the edge pairs that get this far (late SPEC 5.3 state), before the normal is formed.
  // (The same tests as the roles made after their own; the results are the same bit for bit.)
  const Vec3 pa = p0 + s * da, pb = q0 + t * db;
  if (!inside(B, pa) || !inside(A, pb)) return 0;
  const Vec3 n0 = normalized(cross(da, db));
  const Vec3 ma = A.n[kTetEdgeFaces[ea][0]] + A.n[kTetEdgeFaces[ea][1]];
  const Vec3 mb = B.n[kTetEdgeFaces[eb][0]] + B.n[kTetEdgeFaces[eb][1]];
  // one role, P's edge into Q: xp, xq the closest points on P's and Q's edges, sp, sq their
  // weights, mp, mq the sums of P's and Q's face normals at their edges (xp inside Q and xq
  // inside P: tested above)
  auto role = [&](Vec3 n, Vec3 xp, Vec3 xq, double sp, double sq, Vec3 mp, Vec3 mq) {
    if (dot(n, mq) < 0) n = -1.0 * n;
    if (!(dot(n, mp) < 0)) return false;
    const double d = dot(xq - xp, n);
    if (!(d > 0)) return false;
    h.s = sp;
    h.t = sq;
    h.d = d;
    h.n = n;
    return true;
  };
  if (ok_ab && role(n0, pa, pb, s, t, ma, mb)) return 1;
  if (ok_ba && role(-1.0 * n0, pb, pa, t, s, mb, ma)) return 2;
  return 0;
}

// The edge pairs of A's edges `ma` and B's `mb` (bit sets) that edge_hit_either may find in
// contact: bit edge_key(ea, eb) set unless its tests before the roles reject the pair (the
// spheres, nearly parallel lines, the closest points outside the segments, A's point outside B
// or B's outside A: nine in ten of the pairs tested in the late SPEC 5.3 state end there).
// B's six edges are the lanes of one vector loop per edge of A, each lane doing edge_hit_either's
// operations in its order (this file is compiled without contraction: the same bits), so a
// pair rejected here is one edge_hit_either rejects; the few left are tested by it in full.
// (One pair at a time those tests branched on data, most of the count pass's time.)
std::uint64_t edge_candidates(const TetGeom& A, int ma, const TetGeom& B, int mb) {
  if (ma == 0 || mb == 0) return 0;
  constexpr int W = 8;  // B's 6 edges and 2 lanes of padding (copies of edge 0, masked out)
  alignas(64) double qx[W], qy[W], qz[W], bx[W], by[W], bz[W], mx[W], my[W], mz[W], lb[W];
  for (int l = 0; l < W; ++l) {
    const int e = l < 6 ? l : 0;
    const Vec3 q0 = B.x[kTetEdges[e][0]], db = B.x[kTetEdges[e][1]] - q0;
    qx[l] = q0.x, qy[l] = q0.y, qz[l] = q0.z;
    bx[l] = db.x, by[l] = db.y, bz[l] = db.z;
    mx[l] = B.em[e].x, my[l] = B.em[e].y, mz[l] = B.em[e].z;
    lb[l] = B.el[e];
  }
  std::uint64_t out = 0;
  for (int ea = 0; ea < 6; ++ea) {
    if (!(ma >> ea & 1)) continue;
    const Vec3 p0 = A.x[kTetEdges[ea][0]], da = A.x[kTetEdges[ea][1]] - p0, ema = A.em[ea];
    const double la = A.el[ea], a = dot(da, da);
    alignas(64) std::int64_t ok[W];  // (the width of a double: bytes kept GCC 12 from vectorising)
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double dmx = ema.x - mx[l], dmy = ema.y - my[l], dmz = ema.z - mz[l];
      const double dm2 = dmx * dmx + dmy * dmy + dmz * dmz;
      const double reach_ab = 0.5 * (la + lb[l]) + A.tol + B.tol;
      const double reach_ba = 0.5 * (lb[l] + la) + B.tol + A.tol;
      const bool near_ab = !(dm2 > reach_ab * reach_ab), near_ba = !(dm2 > reach_ba * reach_ba);
      const double rx = p0.x - qx[l], ry = p0.y - qy[l], rz = p0.z - qz[l];
      const double e = bx[l] * bx[l] + by[l] * by[l] + bz[l] * bz[l];
      const double b = da.x * bx[l] + da.y * by[l] + da.z * bz[l];
      const double c = da.x * rx + da.y * ry + da.z * rz;
      const double f = bx[l] * rx + by[l] * ry + bz[l] * rz;
      const double den = a * e - b * b;
      const bool ok_ab = near_ab & (den > 1e-6 * a * e), ok_ba = near_ba & (den > 1e-6 * e * a);
      const double s = (b * f - c * e) / den, t = (a * f - b * c) / den;
      bool keep = (ok_ab | ok_ba) & (s > 0.01) & (s < 0.99) & (t > 0.01) & (t < 0.99);
      const double pax = p0.x + s * da.x, pay = p0.y + s * da.y, paz = p0.z + s * da.z;
      const double pbx = qx[l] + t * bx[l], pby = qy[l] + t * by[l], pbz = qz[l] + t * bz[l];
      for (int k = 0; k < 4; ++k) {  // (inside: every face plane within tol)
        keep &= !((pax - B.a0[k].x) * B.n[k].x + (pay - B.a0[k].y) * B.n[k].y + (paz - B.a0[k].z) * B.n[k].z > B.tol);
        keep &= !((pbx - A.a0[k].x) * A.n[k].x + (pby - A.a0[k].y) * A.n[k].y + (pbz - A.a0[k].z) * A.n[k].z > A.tol);
      }
      ok[l] = keep;
    }
    int row = 0;
    for (int l = 0; l < 6; ++l) row |= static_cast<int>(ok[l]) << l;
    out |= static_cast<std::uint64_t>(row & mb) << (6 * ea);
  }
  return out;
}

}  // namespace cdem
