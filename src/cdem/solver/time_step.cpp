#include "cdem/solver/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "cdem/core/sym_eigen.hpp"

namespace cdem {

StableStep stable_time_step(const Model& m, double safety, bool contact_share) {
  StableStep s;
  s.dt_block = std::numeric_limits<double>::infinity();
  s.dt_spring = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    const auto& mat = m.block_materials[m.block_material[b]];
    if (!mat.explosive.empty()) continue;  // explosive blocks: limited by their EOS (issue 3)
    const auto k = m.block_material[b];
    const double cp = std::sqrt((m.mat_lambda[k] + 2.0 * m.mat_shear[k]) / mat.density);
    const double d = m.block_altitude0[b] / cp;
    if (d < s.dt_block) {
      s.dt_block = d;
      s.block = static_cast<std::int64_t>(b);
    }
  }
  // Spring stiffness at each node, summed in ascending spring order.
  std::vector<double> k_node(m.n_nodes(), 0.0);
  std::vector<std::int32_t> count(contact_share ? m.n_nodes() : 0, 0);
  for (std::size_t sp = 0; sp < m.n_springs(); ++sp) {
    k_node[m.sp_a[sp]] += m.sp_kn[sp];
    k_node[m.sp_b[sp]] += m.sp_kn[sp];
    if (contact_share) ++count[m.sp_a[sp]], ++count[m.sp_b[sp]];
  }
  if (contact_share)
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      if (count[n] > 0) k_node[n] *= (count[n] + 1.0) / count[n];
  for (std::size_t n = 0; n < m.n_nodes(); ++n) {
    const double k = k_node[n];
    if (k <= 0) continue;
    const double d = std::sqrt(2.0 * m.mass[n] / k);
    if (d < s.dt_spring) {
      s.dt_spring = d;
      s.node = static_cast<std::int64_t>(n);
    }
  }
  s.limit = s.dt_spring < s.dt_block ? "springs" : "blocks";
  s.dt = safety * std::min(s.dt_block, s.dt_spring);
  s.safety = safety;
  return s;
}

double block_omega2(const Model& m, std::size_t b) {
  const ElemType type = m.block_type[b];
  const int nn = nodes_of(type);
  const int dim = type == ElemType::Tet4 ? 3 : 2;
  const auto k = m.block_material[b];
  const double lam = m.mat_lambda[k], G = m.mat_shear[k];
  const double* g = m.geom.data() + m.geom_offset[b];
  // Integration points: weight (volume share) and the gradients dN_i/dX_a of the nodes.
  struct Point {
    double w;
    double grad[4][3];
  };
  Point pts[4];
  int npts = 1;
  if (type == ElemType::Tri3) {
    // Dm^-1 = [[g0, g1], [g2, g3]]: grad N_1 = (g0, g1), grad N_2 = (g2, g3), N_0 = -(sum)
    pts[0] = {m.block_volume0[b], {{-(g[0] + g[2]), -(g[1] + g[3]), 0}, {g[0], g[1], 0}, {g[2], g[3], 0}, {}}};
  } else if (type == ElemType::Quad4) {
    npts = 4;
    for (int q = 0; q < 4; ++q) {
      const double* gq = g + 9 * q;
      pts[q].w = gq[0];
      for (int i = 0; i < 4; ++i) {
        pts[q].grad[i][0] = gq[1 + 2 * i];
        pts[q].grad[i][1] = gq[2 + 2 * i];
        pts[q].grad[i][2] = 0;
      }
    }
  } else {
    // grad N_j = row j-1 of Dm^-1 (j = 1..3), grad N_0 = -(sum)
    pts[0].w = m.block_volume0[b];
    for (int c = 0; c < 3; ++c) {
      pts[0].grad[1][c] = g[c];
      pts[0].grad[2][c] = g[3 + c];
      pts[0].grad[3][c] = g[6 + c];
      pts[0].grad[0][c] = -(g[c] + g[3 + c] + g[6 + c]);
    }
  }
  const int ndof = dim * nn;
  double K[12][12] = {};
  // K_{ia,jb} = sum_q w_q [lambda g_ia g_jb + G (g_ib g_ja + delta_ab g_i . g_j)]
  for (int q = 0; q < npts; ++q) {
    const auto& p = pts[q];
    for (int i = 0; i < nn; ++i)
      for (int j = 0; j < nn; ++j) {
        double gij = 0;
        for (int c = 0; c < dim; ++c) gij += p.grad[i][c] * p.grad[j][c];
        for (int a = 0; a < dim; ++a)
          for (int bb = 0; bb < dim; ++bb)
            K[dim * i + a][dim * j + bb] +=
                p.w * (lam * p.grad[i][a] * p.grad[j][bb] + G * p.grad[i][bb] * p.grad[j][a] +
                       (a == bb ? G * gij : 0.0));
      }
  }
  const auto n0 = m.block_first_node[b];
  for (int i = 0; i < ndof; ++i)
    for (int j = 0; j < ndof; ++j)
      K[i][j] /= std::sqrt(m.mass[n0 + i / dim] * m.mass[n0 + j / dim]);
  return sym_max_eigenvalue(K, ndof);
}

MassScaling scale_masses_to_bound(Model& m, double bound) {
  MassScaling ms;
  ms.bound = bound;
  for (double mn : m.mass) ms.total += mn;
  if (!(bound > 0)) return ms;
  // omega_e^2 > (2 / bound)^2: the block's bound is below the one asked
  const double w2_max = 4.0 / (bound * bound);
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    // (explosive blocks: limited by their EOS; blocks holding a bar's charge: their mass holds the
    // products' share, products_mass, which scaling would misstate)
    const BlockMaterial& mat = m.block_materials[m.block_material[b]];
    if (!mat.explosive.empty() || mat.charge_fraction > 0) continue;
    const double o2 = block_omega2(m, b);
    if (!(o2 > w2_max)) continue;
    const double s = o2 / w2_max;
    for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n) {
      ms.added += (s - 1.0) * m.mass[n];
      m.mass[n] *= s;
      if (!m.inv_mass.empty()) m.inv_mass[n] = 1.0 / m.mass[n];
    }
    ++ms.blocks;
    ms.max_factor = std::max(ms.max_factor, s);
  }
  return ms;
}

BoundQuantiles block_bound_quantiles(const Model& m) {
  std::vector<double> d;
  d.reserve(m.n_blocks());
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    if (!m.block_materials[m.block_material[b]].explosive.empty()) continue;
    const double o2 = block_omega2(m, b);
    if (o2 > 0) d.push_back(2.0 / std::sqrt(o2));
  }
  BoundQuantiles q;
  if (d.empty()) return q;
  std::sort(d.begin(), d.end());
  auto at = [&](double f) { return d[std::min(d.size() - 1, static_cast<std::size_t>(f * static_cast<double>(d.size())))]; };
  q.min = d.front();
  q.q001 = at(0.001);
  q.q01 = at(0.01);
  q.q1 = at(0.1);
  return q;
}

std::string describe_mass_scaling(const MassScaling& ms, double dt_asked, int dim) {
  const char* unit = dim == 2 ? "kg/m" : "kg";
  if (ms.blocks == 0)
    return fmt::format("to a step of {:.4g} s (element bound {:.4g} s): no block is below it, nothing added",
                       dt_asked, ms.bound);
  return fmt::format("to a step of {:.4g} s (element bound {:.4g} s): {} blocks made up to {:.3g} times "
                     "heavier, {:.4g} {} added to the model's {:.6g} {} ({:.3g} of it)",
                     dt_asked, ms.bound, ms.blocks, ms.max_factor, ms.added, unit, ms.total, unit,
                     ms.share());
}

StableStep stable_time_step_tied(const Model& m, double safety, double eta, double* omega2_max) {
  StableStep s;
  double w2 = 0;
  for (std::size_t b = 0; b < m.n_blocks(); ++b) {
    const auto& mat = m.block_materials[m.block_material[b]];
    if (!mat.explosive.empty()) continue;  // explosive blocks: limited by their EOS
    const double o2 = block_omega2(m, b);
    if (o2 > w2) {
      w2 = o2;
      s.block = static_cast<std::int64_t>(b);
    }
  }
  if (omega2_max) *omega2_max = w2;
  const double inf = std::numeric_limits<double>::infinity();
  s.dt_block = w2 > 0 ? 2.0 / std::sqrt(w2) : inf;
  s.dt_spring = w2 > 0 && eta > 0 ? 2.0 / std::sqrt(eta * w2) : inf;
  s.limit = "blocks (tied interfaces)";
  s.dt = safety * (w2 > 0 ? 2.0 / std::sqrt(w2 * (1.0 + eta)) : inf);
  s.safety = safety;
  return s;
}

}  // namespace cdem
