#include "cdem/analysis/reactions.hpp"

#include <algorithm>
#include <cmath>

#include "cdem/physics/integrate.hpp"

namespace cdem {

ReactionMeter::ReactionMeter(const Model& m, const std::vector<BoundaryCondition>& boundaries,
                             Vec3 gravity, const std::string& where)
    : gravity_(gravity) {
  // One Boundaries per constraint [[boundary]] (the same preparation as the solver's, so the
  // same nodes, roller normals and tables).
  for (std::size_t k = 0; k < boundaries.size(); ++k) {
    const BoundaryType t = boundaries[k].type;
    if (t != BoundaryType::Fixed && t != BoundaryType::Roller && t != BoundaryType::Velocity) continue;
    bcs_.push_back(prepare_boundaries(m, {boundaries[k]}, gravity, where));
    const std::string& name = boundaries[k].faces;
    auto it = std::find(sets_.begin(), sets_.end(), name);
    if (it == sets_.end()) {
      sets_.push_back(name);
      it = sets_.end() - 1;
    }
    bc_set_.push_back(static_cast<std::int32_t>(it - sets_.begin()));
  }
  force_.assign(sets_.size(), Vec3{});
  if (sets_.empty()) return;
  constrained_.assign(m.n_nodes(), 0);
  for (const auto& b : bcs_)
    for (const auto& cn : b.constraints) constrained_[cn.node] = 1;
  if (m.tied) {
    std::vector<std::uint8_t> seen(m.n_vertices(), 0);
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      if (constrained_[n] && !seen[m.node_vertex[n]]) {
        seen[m.node_vertex[n]] = 1;
        vertices_.push_back(m.node_vertex[n]);
      }
    std::sort(vertices_.begin(), vertices_.end());
    for (auto vx : vertices_)
      for (auto k = m.vtx_offset[vx]; k < m.vtx_offset[vx + 1]; ++k) nodes_.push_back(m.vtx_nodes[k]);
  } else {
    for (std::size_t n = 0; n < m.n_nodes(); ++n)
      if (constrained_[n]) nodes_.push_back(static_cast<std::int32_t>(n));
  }
  std::sort(nodes_.begin(), nodes_.end());
  v_old_.resize(nodes_.size());
}

void ReactionMeter::before_step(const Model& m) {
  for (std::size_t i = 0; i < nodes_.size(); ++i) v_old_[i] = m.v[nodes_[i]];
}

namespace {
// The free velocity v(n+1/2) of mass `mass` under force f (gravity included) from v0, with the
// viscous coefficient c and local damping alpha: integrate.cpp's update.
Vec3 free_velocity(Vec3 v0, Vec3 f, double mass, double c, double alpha, double dt) {
  if (alpha > 0) {
    Vec3 fd{};
    for (int k = 0; k < 3; ++k)
      fd[k] = -alpha * std::abs(f[k]) * (v0[k] > 0 ? 1.0 : (v0[k] < 0 ? -1.0 : 0.0));
    f += fd;
  }
  if (c != 0) {
    const double cdt = 0.5 * c * dt;
    return ((1.0 - cdt) * v0 + (dt / mass) * f) / (1.0 + cdt);
  }
  return v0 + (dt / mass) * f;
}
}  // namespace

double ReactionMeter::after_step(const Model& m, double dt, double t_mid) {
  for (auto& f : force_) f = Vec3{};
  if (sets_.empty()) return 0;
  auto v0_of = [&](std::int32_t n) {
    return v_old_[static_cast<std::size_t>(std::lower_bound(nodes_.begin(), nodes_.end(), n) - nodes_.begin())];
  };
  const bool viscous = !m.damping.empty(), local = !m.local_damping.empty();
  double worst = 0;
  // Applies the constraints of `nodes` (in order) to v, each boundary's change of velocity times
  // M / dt going to its face set.
  auto constrain = [&](const std::int32_t* nodes, std::int32_t count, Vec3 v, double mass) {
    for (std::int32_t k = 0; k < count; ++k) {
      const std::int32_t n = nodes[k];
      if (!constrained_[n]) continue;
      for (std::size_t b = 0; b < bcs_.size(); ++b) {
        const Vec3 vc = constrain_velocity(bcs_[b], n, v, t_mid);
        force_[bc_set_[b]] += (mass / dt) * (vc - v);
        v = vc;
      }
    }
    return v;
  };
  if (m.tied) {
    const std::int32_t* nodes = m.vtx_nodes.data();
    for (auto vx : vertices_) {
      const std::int32_t o1 = m.vtx_offset[vx + 1];
      for (std::int32_t p = m.vtx_offset[vx]; p < o1;) {
        std::int32_t q = p + 1;
        while (q < o1 && !m.vtx_run[q]) ++q;
        bool any = false;
        for (std::int32_t k = p; k < q; ++k) any = any || constrained_[nodes[k]];
        if (any) {
          const ClusterSums sums = cluster_sums(m, nodes, p, q, viscous, local);
          const double mass = sums.mass, cm = sums.cm, am = sums.am;
          Vec3 f = sums.f;
          f += mass * gravity_;
          const Vec3 vfree = free_velocity(v0_of(nodes[p]), f, mass, cm / mass, am / mass, dt);
          const Vec3 vc = constrain(nodes + p, q - p, vfree, mass);
          worst = std::max(worst, norm(vc - m.v[nodes[p]]));
        }
        p = q;
      }
    }
  } else {
    for (auto n : nodes_) {
      const double mass = m.mass[n];
      const Vec3 vfree = free_velocity(v0_of(n), m.f[n] + mass * gravity_, mass,
                                       viscous ? m.damping[n] : 0.0,
                                       local ? m.local_damping[n] : 0.0, dt);
      const Vec3 vc = constrain(&n, 1, vfree, mass);
      worst = std::max(worst, norm(vc - m.v[n]));
    }
  }
  return worst;
}

}  // namespace cdem
