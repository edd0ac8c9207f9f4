#include "cdem/physics/stiffness_damping.hpp"

#include <algorithm>
#include <cmath>

#include "cdem/core/polar.hpp"
#include "cdem/physics/polar_tet.hpp"

namespace cdem {
namespace {

// The co-rotated viscous stress of one integration point in 2D (plane strain): R from the
// polar split of F (as corot_point_2d), E' = sym(R^T F'), S_v = beta C:E', returns P_v = R S_v
// (p00, p01, p10, p11).
struct P2 {
  double p00, p01, p10, p11;
};
inline P2 viscous_2d(double f00, double f01, double f10, double f11, double d00, double d01,
                     double d10, double d11, double blam, double bg) {
  double c, s;
  polar_2d(f00, f01, f10, f11, c, s);
  const double l00 = c * d00 + s * d10, l01 = c * d01 + s * d11;
  const double l10 = -s * d00 + c * d10, l11 = -s * d01 + c * d11;
  const double exx = l00, eyy = l11, exy = 0.5 * (l01 + l10);
  const double tr = exx + eyy;
  const double sxx = blam * tr + 2 * bg * exx, syy = blam * tr + 2 * bg * eyy, sxy = 2 * bg * exy;
  return {c * sxx - s * sxy, c * sxy - s * syy, s * sxx + c * sxy, s * sxy + c * syy};
}

void damp_tri(Model& m, std::int32_t b, double blam, double bg, Vec3* fd) {
  const auto n0 = m.block_first_node[b];
  const double* g = m.geom.data() + m.geom_offset[b];
  const Vec3 x0 = m.x[n0], x1 = m.x[n0 + 1], x2 = m.x[n0 + 2];
  const Vec3 v0 = m.v[n0], v1 = m.v[n0 + 1], v2 = m.v[n0 + 2];
  auto grad = [g](double a0, double a1, double b0, double b1, double out[4]) {
    out[0] = a0 * g[0] + a1 * g[2];
    out[1] = a0 * g[1] + a1 * g[3];
    out[2] = b0 * g[0] + b1 * g[2];
    out[3] = b0 * g[1] + b1 * g[3];
  };
  double f[4], d[4];
  grad(x1.x - x0.x, x2.x - x0.x, x1.y - x0.y, x2.y - x0.y, f);
  grad(v1.x - v0.x, v2.x - v0.x, v1.y - v0.y, v2.y - v0.y, d);
  const P2 p = viscous_2d(f[0], f[1], f[2], f[3], d[0], d[1], d[2], d[3], blam, bg);
  const double vol = m.block_volume0[b];
  const double gx[3] = {-(g[0] + g[2]), g[0], g[2]};
  const double gy[3] = {-(g[1] + g[3]), g[1], g[3]};
  for (int i = 0; i < 3; ++i)
    fd[i] = {-vol * (p.p00 * gx[i] + p.p01 * gy[i]), -vol * (p.p10 * gx[i] + p.p11 * gy[i]), 0.0};
}

void damp_quad(Model& m, std::int32_t b, double blam, double bg, Vec3* fd) {
  const auto n0 = m.block_first_node[b];
  const double* g = m.geom.data() + m.geom_offset[b];
  for (int i = 0; i < 4; ++i) fd[i] = {};
  for (int q = 0; q < 4; ++q) {
    const double* gq = g + 9 * q;
    const double wq = gq[0];
    double f00 = 0, f01 = 0, f10 = 0, f11 = 0, d00 = 0, d01 = 0, d10 = 0, d11 = 0;
    for (int i = 0; i < 4; ++i) {
      const double gxi = gq[1 + 2 * i], gyi = gq[2 + 2 * i];
      const Vec3 x = m.x[n0 + i], v = m.v[n0 + i];
      f00 += x.x * gxi;
      f01 += x.x * gyi;
      f10 += x.y * gxi;
      f11 += x.y * gyi;
      d00 += v.x * gxi;
      d01 += v.x * gyi;
      d10 += v.y * gxi;
      d11 += v.y * gyi;
    }
    const P2 p = viscous_2d(f00, f01, f10, f11, d00, d01, d10, d11, blam, bg);
    for (int i = 0; i < 4; ++i) {
      const double gxi = gq[1 + 2 * i], gyi = gq[2 + 2 * i];
      fd[i].x -= wq * (p.p00 * gxi + p.p01 * gyi);
      fd[i].y -= wq * (p.p10 * gxi + p.p11 * gyi);
    }
  }
}

void damp_tet(Model& m, std::int32_t b, double blam, double bg, Vec3* fd) {
  const auto n0 = m.block_first_node[b];
  const double* g = m.geom.data() + m.geom_offset[b];
  Mat3 ds, dv, dminv;
  for (int j = 0; j < 3; ++j) {
    const Vec3 d = m.x[n0 + 1 + j] - m.x[n0];
    const Vec3 w = m.v[n0 + 1 + j] - m.v[n0];
    ds(0, j) = d.x; ds(1, j) = d.y; ds(2, j) = d.z;
    dv(0, j) = w.x; dv(1, j) = w.y; dv(2, j) = w.z;
  }
  for (int q = 0; q < 9; ++q) dminv.m[q] = g[q];
  Mat3 R;
  polar_3d_tet(ds * dminv, R);  // identity for an inverted block (the run stops on it)
  const Mat3 L = transpose(R) * (dv * dminv);
  const double exx = L(0, 0), eyy = L(1, 1), ezz = L(2, 2);
  const double exy = 0.5 * (L(0, 1) + L(1, 0)), eyz = 0.5 * (L(1, 2) + L(2, 1)),
               exz = 0.5 * (L(0, 2) + L(2, 0));
  const double tr = exx + eyy + ezz;
  Mat3 S;
  S(0, 0) = blam * tr + 2 * bg * exx;
  S(1, 1) = blam * tr + 2 * bg * eyy;
  S(2, 2) = blam * tr + 2 * bg * ezz;
  S(0, 1) = S(1, 0) = 2 * bg * exy;
  S(1, 2) = S(2, 1) = 2 * bg * eyz;
  S(0, 2) = S(2, 0) = 2 * bg * exz;
  const Mat3 P = R * S;
  const double vol = m.block_volume0[b];
  Vec3 fsum{};
  for (int j = 0; j < 3; ++j) {
    const Vec3 gn{dminv(j, 0), dminv(j, 1), dminv(j, 2)};
    fd[1 + j] = -vol * (P * gn);
    fsum += fd[1 + j];
  }
  fd[0] = -fsum;
}

}  // namespace

double max_stiffness_damping(const Model& m) {
  double beta = 0;
  for (const auto& g : m.groups) {
    if (g.kind != BlockKind::Elastic) continue;
    for (std::int32_t b = g.begin; b < g.end; ++b) beta = std::max(beta, m.mat_beta[m.block_material[b]]);
  }
  return beta;
}

double damped_stable_step(double dt_undamped, double beta) {
  if (!(beta > 0) || !(dt_undamped > 0) || !std::isfinite(dt_undamped)) return dt_undamped;
  const double zeta = beta / dt_undamped;
  // sqrt(1 + z^2) - z written as 1 / (sqrt(1 + z^2) + z): no cancellation at large zeta
  return dt_undamped / (std::sqrt(1.0 + zeta * zeta) + zeta);
}

void stiffness_damping_forces(Model& m, std::vector<Vec3>& fd, std::vector<double>& power) {
  for (const auto& g : m.groups) {
    const bool elastic = g.kind == BlockKind::Elastic;
#pragma omp parallel for schedule(static)
    for (std::int32_t b = g.begin; b < g.end; ++b) {
      const auto k = m.block_material[b];
      const double beta = elastic ? m.mat_beta[k] : 0.0;
      const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
      Vec3* f = fd.data() + n0;
      if (!(beta > 0)) {
        for (auto n = n0; n < n1; ++n) fd[n] = {};
        power[b] = 0;
        continue;
      }
      const double blam = beta * m.mat_lambda[k], bg = beta * m.mat_shear[k];
      switch (g.type) {
        case ElemType::Tri3: damp_tri(m, b, blam, bg, f); break;
        case ElemType::Quad4: damp_quad(m, b, blam, bg, f); break;
        case ElemType::Tet4: damp_tet(m, b, blam, bg, f); break;
      }
      double p = 0;
      for (auto n = n0; n < n1; ++n) {
        m.f[n] += fd[n];
        p += dot(fd[n], m.v[n]);
      }
      power[b] = p;
    }
  }
}

}  // namespace cdem
