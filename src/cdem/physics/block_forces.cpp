#include "cdem/physics/block_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cdem/core/loop_split.hpp"
#include "cdem/core/polar.hpp"
#include "cdem/physics/polar_tet.hpp"
#include "cdem/physics/springs.hpp"

namespace cdem {
namespace {

struct ElasticConst {
  double lam, g;
};

// Plane-strain constitutive update in the co-rotated frame for one integration point.
// Inputs F (2x2); outputs first Piola P = R S (2x2), Cauchy sigma (Sym6), energy density, det F.
// The block's initial (in-situ) stress: stress0 is empty when it is zero everywhere
// (Simulation releases it then).
inline Sym6 stress0_of(const Model& m, std::int64_t b) {
  Sym6 s0{};
  if (!m.stress0.empty()) s0 = m.stress0[b];
  return s0;
}

struct Point2D {
  double p00, p01, p10, p11;
  Sym6 sigma;
  double w;
  double j;
};
inline Point2D corot_point_2d(double f00, double f01, double f10, double f11, const ElasticConst& k,
                              const Sym6& s0) {
  double c, s;
  polar_2d(f00, f01, f10, f11, c, s);
  // U = R^T F
  const double u00 = c * f00 + s * f10, u01 = c * f01 + s * f11;
  const double u10 = -s * f00 + c * f10, u11 = -s * f01 + c * f11;
  const double exx = u00 - 1.0, eyy = u11 - 1.0, exy = 0.5 * (u01 + u10);
  const double tr = exx + eyy;
  const double sxx = k.lam * tr + 2 * k.g * exx + s0[0];
  const double syy = k.lam * tr + 2 * k.g * eyy + s0[1];
  const double sxy = 2 * k.g * exy + s0[3];
  const double szz = k.lam * tr + s0[2];  // plane strain: eps_zz = 0
  Point2D out;
  out.p00 = c * sxx - s * sxy;
  out.p01 = c * sxy - s * syy;
  out.p10 = s * sxx + c * sxy;
  out.p11 = s * sxy + c * syy;
  // sigma = R S R^T
  const double cc = c * c, ss = s * s, cs = c * s;
  out.sigma = {cc * sxx - 2 * cs * sxy + ss * syy, ss * sxx + 2 * cs * sxy + cc * syy, szz,
               cs * (sxx - syy) + (cc - ss) * sxy, 0.0, 0.0};
  out.w = 0.5 * k.lam * tr * tr + k.g * (exx * exx + eyy * eyy + 2 * exy * exy) +
          (s0[0] * exx + s0[1] * eyy + 2 * s0[3] * exy);
  out.j = f00 * f11 - f01 * f10;
  return out;
}

// Lame constants of a block from the per-material table (no divisions in the loop).
inline ElasticConst elastic_of(const Model& m, std::int32_t b) {
  const auto k = m.block_material[b];
  return {m.mat_lambda[k], m.mat_shear[k]};
}

void note_inverted(std::int64_t& count, std::int32_t b, std::int32_t* first) {
  ++count;
  if (first) {
#pragma omp critical(cdem_inverted)
    if (*first < 0 || b < *first) *first = b;
  }
}

}  // namespace

std::int64_t block_forces_tri(Model& m, std::int32_t begin, std::int32_t end,
                              std::int32_t* first_inverted, bool gather_springs) {
  std::int64_t inverted = 0;
#pragma omp parallel for schedule(static) reduction(+ : inverted)
  for (std::int32_t b = begin; b < end; ++b) {
    const auto n0 = m.block_first_node[b];
    const double* g = m.geom.data() + m.geom_offset[b];
    const Vec3 x0 = m.x[n0], x1 = m.x[n0 + 1], x2 = m.x[n0 + 2];
    const double d00 = x1.x - x0.x, d01 = x2.x - x0.x, d10 = x1.y - x0.y, d11 = x2.y - x0.y;
    // F = Ds Dm^-1, Dm^-1 = [[g0, g1], [g2, g3]]
    const double f00 = d00 * g[0] + d01 * g[2], f01 = d00 * g[1] + d01 * g[3];
    const double f10 = d10 * g[0] + d11 * g[2], f11 = d10 * g[1] + d11 * g[3];
    const Point2D pt = corot_point_2d(f00, f01, f10, f11, elastic_of(m, b), stress0_of(m, b));
    const double v0 = m.block_volume0[b];
    // grad N_1 = (g0, g1), grad N_2 = (g2, g3), grad N_0 = -(sum)
    const double gx[3] = {-(g[0] + g[2]), g[0], g[2]};
    const double gy[3] = {-(g[1] + g[3]), g[1], g[3]};
    for (int i = 0; i < 3; ++i)
      m.f[n0 + i] = {-v0 * (pt.p00 * gx[i] + pt.p01 * gy[i]),
                     -v0 * (pt.p10 * gx[i] + pt.p11 * gy[i]), 0.0};
    if (gather_springs) add_spring_forces(m, b);
    m.stress[b] = pt.sigma;
    m.strain_energy[b] = v0 * pt.w;
    m.vol_ratio[b] = pt.j;
    if (!(pt.j > 0)) note_inverted(inverted, b, first_inverted);
  }
  return inverted;
}

std::int64_t block_forces_quad(Model& m, std::int32_t begin, std::int32_t end,
                               std::int32_t* first_inverted, bool gather_springs) {
  std::int64_t inverted = 0;
#pragma omp parallel for schedule(static) reduction(+ : inverted)
  for (std::int32_t b = begin; b < end; ++b) {
    const auto n0 = m.block_first_node[b];
    const double* g = m.geom.data() + m.geom_offset[b];
    const ElasticConst k = elastic_of(m, b);
    Vec3 xn[4];
    for (int i = 0; i < 4; ++i) xn[i] = m.x[n0 + i];
    double fx[4] = {0, 0, 0, 0}, fy[4] = {0, 0, 0, 0};
    Sym6 sig{};
    double w = 0, jv = 0, vol = 0;
    for (int q = 0; q < 4; ++q) {
      const double* gq = g + 9 * q;
      const double wq = gq[0];
      double f00 = 0, f01 = 0, f10 = 0, f11 = 0;
      for (int i = 0; i < 4; ++i) {
        const double gxi = gq[1 + 2 * i], gyi = gq[2 + 2 * i];
        f00 += xn[i].x * gxi;
        f01 += xn[i].x * gyi;
        f10 += xn[i].y * gxi;
        f11 += xn[i].y * gyi;
      }
      const Point2D pt = corot_point_2d(f00, f01, f10, f11, k, stress0_of(m, b));
      for (int i = 0; i < 4; ++i) {
        const double gxi = gq[1 + 2 * i], gyi = gq[2 + 2 * i];
        fx[i] -= wq * (pt.p00 * gxi + pt.p01 * gyi);
        fy[i] -= wq * (pt.p10 * gxi + pt.p11 * gyi);
      }
      for (int c = 0; c < 6; ++c) sig[c] += wq * pt.sigma[c];
      w += wq * pt.w;
      jv += wq * pt.j;
      vol += wq;
    }
    for (int i = 0; i < 4; ++i) m.f[n0 + i] = {fx[i], fy[i], 0.0};
    if (gather_springs) add_spring_forces(m, b);
    for (int c = 0; c < 6; ++c) sig[c] /= vol;
    m.stress[b] = sig;
    m.strain_energy[b] = w;
    m.vol_ratio[b] = jv / vol;
    if (!(jv > 0)) note_inverted(inverted, b, first_inverted);
  }
  return inverted;
}

// ---- tet: vectorised across blocks ----
//
// Chunks of kTetChunk consecutive blocks, one block per SIMD lane: SoA temporaries on the stack,
// `omp simd` loops over the lanes (the nodes gathered and the forces scattered through
// block_first_node, the geometry through geom_offset), and the polar decomposition of
// polar_3d_tet run on the whole chunk until every lane has converged, a lane's R frozen from the
// iteration at which its own scalar loop would have stopped. Each block's result depends only
// on its own data: the same for any chunking, range or thread count.
//
// Rounding. The arithmetic is written out operation by operation: contraction off in this
// region and every fused multiply-add an explicit std::fma, placed where GCC 12 (-O3
// -march=native, its default -ffp-contract=fast) fused them in the scalar per-block kernel this
// replaces (polar_3d_tet + Mat3 products). The results are bitwise those of that kernel, and no
// longer depend on how the compiler contracts this code. The rule it followed: a sum of
// products a*b + c*d + e*f is fma(e, f, fma(a, b, c*d)) (dot3), a*b - c*d is fma(a, b, -(c*d))
// (dif2); the exceptions are marked.
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")
namespace {

inline double dot3(double a, double b, double c, double d, double e, double f) {
  return std::fma(e, f, std::fma(a, b, c * d));
}
inline double dif2(double a, double b, double c, double d) { return std::fma(a, b, -(c * d)); }
inline double max2(double a, double b) { return a < b ? b : a; }  // std::max
// det of the row-major 3x3 a..i as core/vec3.hpp det() rounds: c0 a00 - c1 a01 + c2 a02
inline double det3(double c0, double c1, double c2, double a00, double a01, double a02) {
  return std::fma(c2, a02, dif2(c0, a00, c1, a01));
}

// Blocks per chunk (one AVX-512 register of doubles).
constexpr int kTetChunk = 8;

// Blocks b0 .. b0 + n - 1 (n <= kTetChunk; kFull: n == kTetChunk). A partial chunk fills its
// spare lanes with its last block again (same values written to the same places).
// inv[l]: the block of lane l (l < n) is inverted (det F <= 0).
template <bool kStress0, bool kFull>
void tet_chunk(Model& m, std::int32_t b0, int n, bool* inv) {
  constexpr int W = kTetChunk;
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  // x and f as arrays of doubles (node k at 3 k): gathers and scatters with 64-bit indices, so
  // that every type in the loops is 64 bits wide (8 lanes per AVX-512 register).
  const double* __restrict x = &m.x.data()->x;
  double* __restrict fn = &m.f.data()->x;
  const double* __restrict geom = m.geom.data();
  const double* __restrict vol0 = m.block_volume0.data();
  double* __restrict energy = m.strain_energy.data();
  double* __restrict jout = m.vol_ratio.data();
  static_assert(sizeof(Sym6) == 6 * sizeof(double));
  double* __restrict sg = m.stress.data()->data();
  // block; index of its node 0's x, of its geometry, of its stress
  std::int64_t blk[W], xi[W], go[W], si[W];
  double lam_l[W], g_l[W], s0v[6][W];
  for (int l = 0; l < W; ++l) {
    const std::int32_t b = kFull ? b0 + l : b0 + std::min(l, n - 1);
    blk[l] = b;
    si[l] = 6 * static_cast<std::int64_t>(b);
    xi[l] = 3 * static_cast<std::int64_t>(m.block_first_node[b]);
    go[l] = m.geom_offset[b];
    const auto k = m.block_material[b];
    lam_l[l] = m.mat_lambda[k];
    g_l[l] = m.mat_shear[k];
    for (int c = 0; c < 6; ++c) s0v[c][l] = kStress0 ? m.stress0[b][c] : 0.0;
  }
  double F[9][W], R[9][W], G[9][W];
  std::int64_t active[W], bad_lane[W];  // 64-bit flags: masks of the width of a double

  // F = Ds Dm^-1, det F, and the start of the polar decomposition (polar_3d_tet).
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    const std::int64_t i = xi[l], q = go[l];
    const double x0x = x[i], x0y = x[i + 1], x0z = x[i + 2];
    const double d00 = x[i + 3] - x0x, d01 = x[i + 6] - x0x, d02 = x[i + 9] - x0x;
    const double d10 = x[i + 4] - x0y, d11 = x[i + 7] - x0y, d12 = x[i + 10] - x0y;
    const double d20 = x[i + 5] - x0z, d21 = x[i + 8] - x0z, d22 = x[i + 11] - x0z;
    const double g0 = geom[q], g1 = geom[q + 1], g2 = geom[q + 2], g3 = geom[q + 3],
                 g4 = geom[q + 4], g5 = geom[q + 5], g6 = geom[q + 6], g7 = geom[q + 7],
                 g8 = geom[q + 8];
    const double f00 = dot3(d00, g0, d01, g3, d02, g6), f01 = dot3(d00, g1, d01, g4, d02, g7),
                 f02 = dot3(d00, g2, d01, g5, d02, g8);
    const double f10 = dot3(d10, g0, d11, g3, d12, g6), f11 = dot3(d10, g1, d11, g4, d12, g7),
                 f12 = dot3(d10, g2, d11, g5, d12, g8);
    const double f20 = dot3(d20, g0, d21, g3, d22, g6), f21 = dot3(d20, g1, d21, g4, d22, g7),
                 f22 = dot3(d20, g2, d21, g5, d22, g8);
    G[0][l] = g0; G[1][l] = g1; G[2][l] = g2; G[3][l] = g3; G[4][l] = g4;
    G[5][l] = g5; G[6][l] = g6; G[7][l] = g7; G[8][l] = g8;
    F[0][l] = f00; F[1][l] = f01; F[2][l] = f02;
    F[3][l] = f10; F[4][l] = f11; F[5][l] = f12;
    F[6][l] = f20; F[7][l] = f21; F[8][l] = f22;
    const double det = det3(dif2(f11, f22, f12, f21), dif2(f10, f22, f12, f20),
                            dif2(f10, f21, f11, f20), f00, f01, f02);
    jout[blk[l]] = det;
    const bool bad = !(det > 0);
    bad_lane[l] = bad;
    // F orthogonal to round-off: R = F, no iteration (F^T F - I below 1e-15 entrywise)
    double dev = std::abs(dot3(f00, f00, f10, f10, f20, f20) - 1.0);
    dev = max2(dev, std::abs(dot3(f01, f01, f11, f11, f21, f21) - 1.0));
    dev = max2(dev, std::abs(dot3(f02, f02, f12, f12, f22, f22) - 1.0));
    dev = max2(dev, std::abs(dot3(f00, f01, f10, f11, f20, f21)));
    dev = max2(dev, std::abs(dot3(f01, f02, f11, f12, f21, f22)));
    dev = max2(dev, std::abs(dot3(f00, f02, f10, f12, f20, f22)));
    const bool orthogonal = dev < 1e-15;  // evaluated on every lane: no branch
    active[l] = !bad & !orthogonal;
    // inverted: R = identity
    R[0][l] = bad ? 1.0 : f00; R[1][l] = bad ? 0.0 : f01; R[2][l] = bad ? 0.0 : f02;
    R[3][l] = bad ? 0.0 : f10; R[4][l] = bad ? 1.0 : f11; R[5][l] = bad ? 0.0 : f12;
    R[6][l] = bad ? 0.0 : f20; R[7][l] = bad ? 0.0 : f21; R[8][l] = bad ? 1.0 : f22;
  }

  // Newton R <- (R + R^-T) / 2 (polar_newton: tol 1e-9, at most 30 iterations) on every lane,
  // kept on the lanes still iterating; a lane stops after the iteration whose largest change
  // is below the tolerance, as its scalar loop.
  for (int it = 1; it <= 30; ++it) {
    std::int64_t any = 0;
#pragma omp simd reduction(| : any)
    for (int l = 0; l < W; ++l) {
      const double a00 = R[0][l], a01 = R[1][l], a02 = R[2][l];
      const double a10 = R[3][l], a11 = R[4][l], a12 = R[5][l];
      const double a20 = R[6][l], a21 = R[7][l], a22 = R[8][l];
      // inverse(R) as core/vec3.hpp: cofactors times one reciprocal of det
      const double c00 = dif2(a11, a22, a12, a21), c10 = dif2(a10, a22, a12, a20),
                   c20 = dif2(a10, a21, a11, a20);
      const double id = 1.0 / det3(c00, c10, c20, a00, a01, a02);
      const double i01 = id * dif2(a02, a21, a01, a22), i02 = id * dif2(a01, a12, a02, a11);
      // cofactor (1, 0) shares the product a12 a20 with det: -(a10 a22) fused
      const double i10 = id * std::fma(-a10, a22, a12 * a20);
      const double i11 = id * dif2(a00, a22, a02, a20), i12 = id * dif2(a02, a10, a00, a12);
      const double i20 = id * c20, i21 = id * dif2(a01, a20, a00, a21),
                   i22 = id * dif2(a00, a11, a01, a10);
      // R + R^-T ((i, j) of R^-T is (j, i) of the inverse); only the first sum fused
      const double n00 = 0.5 * std::fma(id, c00, a00), n01 = 0.5 * (a01 + i10),
                   n02 = 0.5 * (a02 + i20);
      const double n10 = 0.5 * (a10 + i01), n11 = 0.5 * (a11 + i11), n12 = 0.5 * (a12 + i21);
      const double n20 = 0.5 * (a20 + i02), n21 = 0.5 * (a21 + i12), n22 = 0.5 * (a22 + i22);
      double diff = std::abs(n00 - a00);
      diff = max2(diff, std::abs(n01 - a01));
      diff = max2(diff, std::abs(n02 - a02));
      diff = max2(diff, std::abs(n10 - a10));
      diff = max2(diff, std::abs(n11 - a11));
      diff = max2(diff, std::abs(n12 - a12));
      diff = max2(diff, std::abs(n20 - a20));
      diff = max2(diff, std::abs(n21 - a21));
      diff = max2(diff, std::abs(n22 - a22));
      const bool a = active[l] != 0;
      R[0][l] = a ? n00 : a00; R[1][l] = a ? n01 : a01; R[2][l] = a ? n02 : a02;
      R[3][l] = a ? n10 : a10; R[4][l] = a ? n11 : a11; R[5][l] = a ? n12 : a12;
      R[6][l] = a ? n20 : a20; R[7][l] = a ? n21 : a21; R[8][l] = a ? n22 : a22;
      const bool converged = diff < 1e-9;
      const bool still = a & !converged;
      active[l] = still;
      any |= static_cast<std::int64_t>(still);
    }
    if (!any) break;
  }

  // U = R^T F, eps = sym(U) - I, S = lambda tr(eps) I + 2 G eps + s0, P = R S,
  // f_j = -V0 P grad N_j (grad N_j = row j-1 of Dm^-1, j = 1..3), f_0 = -(sum),
  // sigma = P R^T, energy V0 (lambda/2 tr^2 + G eps:eps + s0:eps).
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    const double f00 = F[0][l], f01 = F[1][l], f02 = F[2][l];
    const double f10 = F[3][l], f11 = F[4][l], f12 = F[5][l];
    const double f20 = F[6][l], f21 = F[7][l], f22 = F[8][l];
    const double r00 = R[0][l], r01 = R[1][l], r02 = R[2][l];
    const double r10 = R[3][l], r11 = R[4][l], r12 = R[5][l];
    const double r20 = R[6][l], r21 = R[7][l], r22 = R[8][l];
    const double g0 = G[0][l], g1 = G[1][l], g2 = G[2][l], g3 = G[3][l], g4 = G[4][l],
                 g5 = G[5][l], g6 = G[6][l], g7 = G[7][l], g8 = G[8][l];
    const double lam = lam_l[l], gs = g_l[l];
    const double s00 = s0v[0][l], s01 = s0v[1][l], s02 = s0v[2][l], s03 = s0v[3][l],
                 s04 = s0v[4][l], s05 = s0v[5][l];
    const double u00 = dot3(r00, f00, r10, f10, r20, f20), u01 = dot3(r00, f01, r10, f11, r20, f21),
                 u02 = dot3(r00, f02, r10, f12, r20, f22);
    const double u10 = dot3(r01, f00, r11, f10, r21, f20), u11 = dot3(r01, f01, r11, f11, r21, f21),
                 u12 = dot3(r01, f02, r11, f12, r21, f22);
    const double u20 = dot3(r02, f00, r12, f10, r22, f20), u21 = dot3(r02, f01, r12, f11, r22, f21),
                 u22 = dot3(r02, f02, r12, f12, r22, f22);
    const double exx = u00 - 1, eyy = u11 - 1, ezz = u22 - 1;
    const double exy = 0.5 * (u01 + u10), eyz = 0.5 * (u12 + u21), exz = 0.5 * (u02 + u20);
    const double tr = exx + eyy + ezz;
    const double g2x = 2 * gs;
    const double sxx = std::fma(lam, tr, g2x * exx) + s00;
    const double syy = std::fma(lam, tr, g2x * eyy) + s01;
    const double szz = std::fma(lam, tr, g2x * ezz) + s02;
    const double sxy = std::fma(g2x, exy, s03);
    const double syz = std::fma(g2x, eyz, s04);
    const double sxz = std::fma(g2x, exz, s05);
    // P = R S (S symmetric)
    const double p00 = dot3(r00, sxx, r01, sxy, r02, sxz), p01 = dot3(r00, sxy, r01, syy, r02, syz),
                 p02 = dot3(r00, sxz, r01, syz, r02, szz);
    const double p10 = dot3(r10, sxx, r11, sxy, r12, sxz), p11 = dot3(r10, sxy, r11, syy, r12, syz),
                 p12 = dot3(r10, sxz, r11, syz, r12, szz);
    const double p20 = dot3(r20, sxx, r21, sxy, r22, sxz), p21 = dot3(r20, sxy, r21, syy, r22, syz),
                 p22 = dot3(r20, sxz, r21, syz, r22, szz);
    const std::int64_t b = blk[l];
    const double v0 = vol0[b];
    const double mv = -v0;
    const double f1x = mv * dot3(p00, g0, p01, g1, p02, g2),
                 f1y = mv * dot3(p10, g0, p11, g1, p12, g2),
                 f1z = mv * dot3(p20, g0, p21, g1, p22, g2);
    const double f2x = mv * dot3(p00, g3, p01, g4, p02, g5),
                 f2y = mv * dot3(p10, g3, p11, g4, p12, g5),
                 f2z = mv * dot3(p20, g3, p21, g4, p22, g5);
    const double f3x = mv * dot3(p00, g6, p01, g7, p02, g8),
                 f3y = mv * dot3(p10, g6, p11, g7, p12, g8),
                 f3z = mv * dot3(p20, g6, p21, g7, p22, g8);
    const std::int64_t i = xi[l];
    fn[i + 3] = f1x; fn[i + 4] = f1y; fn[i + 5] = f1z;
    fn[i + 6] = f2x; fn[i + 7] = f2y; fn[i + 8] = f2z;
    fn[i + 9] = f3x; fn[i + 10] = f3y; fn[i + 11] = f3z;
    fn[i] = -(0.0 + f1x + f2x + f3x);
    fn[i + 1] = -(0.0 + f1y + f2y + f3y);
    fn[i + 2] = -(0.0 + f1z + f2z + f3z);
    const std::int64_t k = si[l];
    sg[k] = dot3(p00, r00, p01, r01, p02, r02);
    sg[k + 1] = dot3(p10, r10, p11, r11, p12, r12);
    sg[k + 2] = dot3(p20, r20, p21, r21, p22, r22);
    sg[k + 3] = dot3(p00, r10, p01, r11, p02, r12);
    sg[k + 4] = dot3(p10, r20, p11, r21, p12, r22);
    sg[k + 5] = dot3(p00, r20, p01, r21, p02, r22);
    // 0.5 lam tr^2 + G (exx^2 + eyy^2 + ezz^2 + 2 (exy^2 + eyz^2 + exz^2)) + s0:eps
    const double sq = std::fma(2.0, dot3(exy, exy, eyz, eyz, exz, exz),
                               dot3(exx, exx, eyy, eyy, ezz, ezz));
    double w = std::fma(tr, (0.5 * lam) * tr, sq * gs);
    w = std::fma(s00, exx, w);
    w = std::fma(s01, eyy, w);
    w = std::fma(s02, ezz, w);
    w = std::fma(2.0, dot3(exy, s03, eyz, s04, exz, s05), w);
    energy[b] = v0 * w;
  }
  for (int l = 0; l < n; ++l) inv[l] = bad_lane[l] != 0;
}

}  // namespace
#pragma GCC pop_options

std::int64_t block_forces_tet(Model& m, std::int32_t begin, std::int32_t end,
                              std::int32_t* first_inverted, bool gather_springs) {
  constexpr int W = kTetChunk;
  const std::int32_t n_chunks = end > begin ? (end - begin + W - 1) / W : 0;
  const bool has_s0 = !m.stress0.empty();
  // (the polar decomposition's iterations and the gather of the opened interfaces' forces cost
  // more where the rock is broken and turning)
  static LoopSplit split;
  return split.run_reduce(n_chunks, std::int64_t{0}, [&](const LoopSplit::Range& r) {
    std::int64_t inverted = 0;
    for (auto c = static_cast<std::int32_t>(r.lo); c < r.hi; ++c) {
      const std::int32_t b0 = begin + c * W;
      const int n = std::min(W, end - b0);
      bool inv[W];
      if (n == W) {
        if (has_s0)
          tet_chunk<true, true>(m, b0, n, inv);
        else
          tet_chunk<false, true>(m, b0, n, inv);
      } else {  // the range's last, partial chunk
        if (has_s0)
          tet_chunk<true, false>(m, b0, n, inv);
        else
          tet_chunk<false, false>(m, b0, n, inv);
      }
      for (int l = 0; l < n; ++l) {
        const std::int32_t b = b0 + l;
        if (gather_springs) {
          add_spring_forces(m, b);
        }
        if (inv[l]) note_inverted(inverted, b, first_inverted);
      }
    }
    return inverted;
  }, std::plus<>{});
}

// The tet kernel one block at a time (the form before vectorisation, kept as the reference the
// chunked kernel reproduces bit for bit; test_tet_kernel.cpp). Outside the fp-contract=off
// region: compiled with GCC's default contraction, as it always was.
std::int64_t block_forces_tet_reference(Model& m, std::int32_t begin, std::int32_t end,
                              std::int32_t* first_inverted, bool gather_springs) {
  std::int64_t inverted = 0;
#pragma omp parallel for schedule(static) reduction(+ : inverted)
  for (std::int32_t b = begin; b < end; ++b) {
    const auto n0 = m.block_first_node[b];
    const double* g = m.geom.data() + m.geom_offset[b];
    const ElasticConst k = elastic_of(m, b);
    const Vec3 x0 = m.x[n0];
    Mat3 ds;
    for (int j = 0; j < 3; ++j) {
      const Vec3 d = m.x[n0 + 1 + j] - x0;
      ds(0, j) = d.x; ds(1, j) = d.y; ds(2, j) = d.z;
    }
    Mat3 dminv;
    for (int q = 0; q < 9; ++q) dminv.m[q] = g[q];
    const Mat3 F = ds * dminv;
    Mat3 R;
    const int iters = polar_3d_tet(F, R);
    const Mat3 U = transpose(R) * F;
    const Sym6 s0 = stress0_of(m, b);
    const double exx = U(0, 0) - 1, eyy = U(1, 1) - 1, ezz = U(2, 2) - 1;
    const double exy = 0.5 * (U(0, 1) + U(1, 0)), eyz = 0.5 * (U(1, 2) + U(2, 1)),
                 exz = 0.5 * (U(0, 2) + U(2, 0));
    const double tr = exx + eyy + ezz;
    Mat3 S;
    S(0, 0) = k.lam * tr + 2 * k.g * exx + s0[0];
    S(1, 1) = k.lam * tr + 2 * k.g * eyy + s0[1];
    S(2, 2) = k.lam * tr + 2 * k.g * ezz + s0[2];
    S(0, 1) = S(1, 0) = 2 * k.g * exy + s0[3];
    S(1, 2) = S(2, 1) = 2 * k.g * eyz + s0[4];
    S(0, 2) = S(2, 0) = 2 * k.g * exz + s0[5];
    const Mat3 P = R * S;
    const double v0 = m.block_volume0[b];
    // grad N_j (j = 1..3) = row j-1 of Dm^-1; grad N_0 = -(sum)
    Vec3 fsum{};
    for (int j = 0; j < 3; ++j) {
      const Vec3 gn{dminv(j, 0), dminv(j, 1), dminv(j, 2)};
      const Vec3 fj = -v0 * (P * gn);
      m.f[n0 + 1 + j] = fj;
      fsum += fj;
    }
    m.f[n0] = -fsum;
    if (gather_springs) add_spring_forces(m, b);
    const Mat3 sig = P * transpose(R);
    m.stress[b] = {sig(0, 0), sig(1, 1), sig(2, 2), sig(0, 1), sig(1, 2), sig(0, 2)};
    m.strain_energy[b] =
        v0 * (0.5 * k.lam * tr * tr +
              k.g * (exx * exx + eyy * eyy + ezz * ezz + 2 * (exy * exy + eyz * eyz + exz * exz)) +
              s0[0] * exx + s0[1] * eyy + s0[2] * ezz + 2 * (s0[3] * exy + s0[4] * eyz + s0[5] * exz));
    m.vol_ratio[b] = det(F);
    if (iters < 0) note_inverted(inverted, b, first_inverted);
  }
  return inverted;
}

std::int64_t block_forces(Model& m, std::int32_t* first_inverted, bool gather_springs,
                          std::int32_t lo, std::int32_t hi) {
  std::int64_t inverted = 0;
  const bool gs = gather_springs;
  for (const auto& g : m.groups) {
    const std::int32_t begin = std::max(g.begin, lo), end = std::min(g.end, hi);
    if (begin >= end) continue;
    if (g.kind != BlockKind::Elastic) {
      const std::int64_t nb = m.block_first_node[begin], ne = m.block_first_node[end];
      std::fill(m.f.begin() + nb, m.f.begin() + ne, Vec3{});
      if (gs) {
#pragma omp parallel for schedule(static)
        for (std::int32_t b = begin; b < end; ++b) add_spring_forces(m, b);
      }
      continue;
    }
    switch (g.type) {
      case ElemType::Tri3: inverted += block_forces_tri(m, begin, end, first_inverted, gs); break;
      case ElemType::Quad4: inverted += block_forces_quad(m, begin, end, first_inverted, gs); break;
      case ElemType::Tet4: inverted += block_forces_tet(m, begin, end, first_inverted, gs); break;
    }
  }
  return inverted;
}

}  // namespace cdem
