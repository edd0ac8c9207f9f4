#include "cdem/physics/block_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

std::int64_t block_forces_tet(Model& m, std::int32_t begin, std::int32_t end,
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

std::int64_t block_forces(Model& m, std::int32_t* first_inverted, bool gather_springs) {
  std::int64_t inverted = 0;
  const bool gs = gather_springs;
  for (const auto& g : m.groups) {
    if (g.kind != BlockKind::Elastic) {
      const std::int64_t nb = m.block_first_node[g.begin], ne = m.block_first_node[g.end];
      std::fill(m.f.begin() + nb, m.f.begin() + ne, Vec3{});
      if (gs) {
#pragma omp parallel for schedule(static)
        for (std::int32_t b = g.begin; b < g.end; ++b) add_spring_forces(m, b);
      }
      continue;
    }
    switch (g.type) {
      case ElemType::Tri3: inverted += block_forces_tri(m, g.begin, g.end, first_inverted, gs); break;
      case ElemType::Quad4: inverted += block_forces_quad(m, g.begin, g.end, first_inverted, gs); break;
      case ElemType::Tet4: inverted += block_forces_tet(m, g.begin, g.end, first_inverted, gs); break;
    }
  }
  return inverted;
}

}  // namespace cdem
