#include "cdem/physics/boundaries.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "cdem/core/error.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {

Boundaries prepare_boundaries(const Model& m, const std::vector<BoundaryCondition>& bcs,
                              Vec3 gravity, const std::string& where) {
  Boundaries b;
  b.gravity = gravity;
  std::vector<std::int32_t> nodes;
  for (std::size_t k = 0; k < bcs.size(); ++k) {
    const auto& bc = bcs[k];
    const auto* set = m.facet_set(bc.faces);
    if (!set) {
      std::string names;
      for (const auto& s : m.facet_sets) names += (names.empty() ? "'" : ", '") + s.name + "'";
      throw InputError(fmt::format("{}: key 'boundary[{}].faces': no face set '{}' in the mesh "
                                   "(its face sets are {})",
                                   where, k, bc.faces, names.empty() ? "none" : names));
    }
    const auto table = static_cast<std::int32_t>(b.tables.size());
    b.tables.push_back(bc.table);
    if (bc.type == BoundaryType::Pressure || bc.type == BoundaryType::NonReflecting) {
      for (const auto& f : set->facets) {
        Boundaries::LoadFacet lf{f, 0, bc.value, 0.0, table, {-1, -1, -1}};
        if (bc.type == BoundaryType::NonReflecting) {
          const auto& mat = m.block_materials[m.block_material[f.block]];
          lf.kind = 1;
          lf.a = mat.density * mat.cp();  // sigma_n = -rho c_p v_n (Lysmer & Kuhlemeyer 1969)
          lf.b = mat.density * mat.cs();  // tau = -rho c_s v_s
        }
        b.loads.push_back(lf);
        for (int q = 0; q < f.count(); ++q) nodes.push_back(f.nodes[q]);
      }
      continue;
    }
    // Velocity constraints: one per node; a roller's normal is the mean facet normal there.
    std::map<std::int32_t, Vec3> normals;
    for (const auto& f : set->facets) {
      Vec3 p[3];
      for (int q = 0; q < f.count(); ++q) p[q] = m.X(f.nodes[q]);
      const Vec3 a = face_area_vector(std::span<const Vec3>(p, f.count()), f.count());
      for (int q = 0; q < f.count(); ++q) normals[f.nodes[q]] += a;
    }
    for (const auto& [n, a] : normals) {
      Boundaries::Constraint cn{n, 0, {}, table, -1};
      if (bc.type == BoundaryType::Roller) {
        cn.kind = 1;
        cn.dir = normalized(a);
      } else if (bc.type == BoundaryType::Velocity) {
        cn.kind = 2;
        cn.dir = bc.direction;
      }
      b.constraints.push_back(cn);
      nodes.push_back(n);
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  auto slot = [&](std::int32_t n) {
    return static_cast<std::int32_t>(std::lower_bound(nodes.begin(), nodes.end(), n) - nodes.begin());
  };
  for (auto& cn : b.constraints) cn.slot = slot(cn.node);
  for (auto& lf : b.loads)
    for (int q = 0; q < lf.facet.count(); ++q) lf.slot[q] = slot(lf.facet.nodes[q]);
  b.work_nodes = nodes;
  b.node_load_offset.assign(nodes.size() + 1, 0);
  for (const auto& lf : b.loads)
    for (int q = 0; q < lf.facet.count(); ++q) ++b.node_load_offset[lf.slot[q] + 1];
  for (std::size_t i = 0; i < nodes.size(); ++i) b.node_load_offset[i + 1] += b.node_load_offset[i];
  b.node_load_entry.assign(b.node_load_offset.back(), -1);
  {
    std::vector<std::int32_t> fill(b.node_load_offset.begin(), b.node_load_offset.end() - 1);
    for (std::size_t l = 0; l < b.loads.size(); ++l)  // facet order, then q: the serial order
      for (int q = 0; q < b.loads[l].facet.count(); ++q)
        b.node_load_entry[fill[b.loads[l].slot[q]]++] = static_cast<std::int32_t>(3 * l + q);
  }
  b.load_force.assign(3 * b.loads.size(), Vec3{});
  b.v_old.resize(nodes.size());
  b.con_order.resize(b.constraints.size());
  std::iota(b.con_order.begin(), b.con_order.end(), 0);
  std::stable_sort(b.con_order.begin(), b.con_order.end(), [&b](std::int32_t p, std::int32_t q) {
    return b.constraints[p].node < b.constraints[q].node;
  });
  for (auto k : b.con_order) b.con_node.push_back(b.constraints[k].node);
  return b;
}

namespace {
inline Vec3 apply_one(const Boundaries& b, const Boundaries::Constraint& c, Vec3 v, double t) {
  switch (c.kind) {
    case 0: return {};
    case 1: return v - dot(v, c.dir) * c.dir;
    case 2: return b.tables[c.table](t) * c.dir;
  }
  return v;
}
}  // namespace

Vec3 constrain_velocity(const Boundaries& b, std::int32_t n, Vec3 v, double t) {
  auto it = std::lower_bound(b.con_node.begin(), b.con_node.end(), n);
  for (; it != b.con_node.end() && *it == n; ++it)
    v = apply_one(b, b.constraints[b.con_order[it - b.con_node.begin()]], v, t);
  return v;
}

void boundary_forces(Model& m, Boundaries& b, double t) {
  const auto nl = static_cast<std::int64_t>(b.loads.size());
  const auto nw = static_cast<std::int64_t>(b.work_nodes.size());
  if (nl == 0 && nw == 0) return;
#pragma omp parallel
  {
    // 1. Each facet's force on each of its nodes (reads x and v only).
#pragma omp for schedule(static)
    for (std::int64_t l = 0; l < nl; ++l) {
      const auto& lf = b.loads[l];
      const int k = lf.facet.count();
      Vec3 p[3];
      for (int q = 0; q < k; ++q) p[q] = m.x[lf.facet.nodes[q]];
      const Vec3 av = face_area_vector(std::span<const Vec3>(p, k), k);  // outward, |av| = area
      Vec3* out = b.load_force.data() + 3 * l;
      if (lf.kind == 0) {
        const Vec3 fn = (-lf.a * b.tables[lf.table](t) / k) * av;  // pressure pushes inward
        for (int q = 0; q < k; ++q) out[q] = fn;
      } else {
        const double area = norm(av);
        const Vec3 n = av / area;
        for (int q = 0; q < k; ++q) {
          const Vec3 v = m.v[lf.facet.nodes[q]];
          const double vn = dot(v, n);
          out[q] = (-area / k) * (lf.a * vn * n + lf.b * (v - vn * n));
        }
      }
    }
    // 2. Per boundary node: v(n-1/2), and its facet forces added to f one by one in the serial
    // order (facet by facet), so the sums do not depend on the thread count.
#pragma omp for schedule(static)
    for (std::int64_t i = 0; i < nw; ++i) {
      const auto nd = b.work_nodes[i];
      b.v_old[i] = m.v[nd];
      for (auto e = b.node_load_offset[i]; e < b.node_load_offset[i + 1]; ++e)
        m.f[nd] += b.load_force[b.node_load_entry[e]];
    }
  }
}

void apply_constraints(Model& m, Boundaries& b, double t, double dt, std::vector<double>& terms) {
  terms.clear();
  for (const auto& c : b.constraints) {
    Vec3& v = m.v[c.node];
    const Vec3 vfree = v;
    v = apply_one(b, c, v, t);
    const Vec3 reaction = (m.mass[c.node] / dt) * (v - vfree);
    terms.insert(terms.end(), {dot(reaction, 0.5 * (b.v_old[c.slot] + v)), dot(reaction, v)});
  }
}

void load_work_terms(const Model& m, Boundaries& b) {
  // Each node's four terms formed in parallel (the velocities were just written by every
  // thread).
  const auto nw = static_cast<std::int64_t>(b.work_nodes.size());
  b.work_terms.resize(4 * static_cast<std::size_t>(nw));
  double* const terms = b.work_terms.data();
#pragma omp parallel for schedule(static) if (nw > 1024)
  for (std::int64_t i = 0; i < nw; ++i) {
    // The node's pressure and dashpot forces of the step, summed from the facet forces (kept
    // in load_force until the next boundary_forces) in the serial order.
    Vec3 fl{}, fd{};
    for (auto e = b.node_load_offset[i]; e < b.node_load_offset[i + 1]; ++e) {
      const auto entry = b.node_load_entry[e];
      if (b.loads[entry / 3].kind == 0)
        fl += b.load_force[entry];
      else
        fd += b.load_force[entry];
    }
    const Vec3 v1 = m.v[b.work_nodes[i]];
    const Vec3 vmid = 0.5 * (b.v_old[i] + v1);
    terms[4 * i] = dot(fl, vmid);
    terms[4 * i + 1] = dot(fd, vmid);
    terms[4 * i + 2] = dot(fl, v1);
    terms[4 * i + 3] = dot(fd, v1);
  }
}

}  // namespace cdem
