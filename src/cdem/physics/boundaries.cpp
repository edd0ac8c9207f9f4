#include "cdem/physics/boundaries.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "cdem/core/error.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {

Boundaries prepare_boundaries(const Model& m, const Case& c) {
  Boundaries b;
  b.gravity = c.gravity;
  std::vector<std::int32_t> nodes;
  for (std::size_t k = 0; k < c.boundaries.size(); ++k) {
    const auto& bc = c.boundaries[k];
    const auto* set = m.facet_set(bc.faces);
    if (!set) {
      std::string names;
      for (const auto& s : m.facet_sets) names += (names.empty() ? "'" : ", '") + s.name + "'";
      throw InputError(fmt::format("{}: key 'boundary[{}].faces': no face set '{}' in the mesh "
                                   "(its face sets are {})",
                                   c.path, k, bc.faces, names.empty() ? "none" : names));
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
      for (int q = 0; q < f.count(); ++q) p[q] = m.X[f.nodes[q]];
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
  b.v_old.resize(nodes.size());
  b.f_load.resize(nodes.size());
  b.f_dash.resize(nodes.size());
  return b;
}

void boundary_forces(Model& m, Boundaries& b, double t) {
  for (std::size_t i = 0; i < b.work_nodes.size(); ++i) {
    b.v_old[i] = m.v[b.work_nodes[i]];
    b.f_load[i] = {};
    b.f_dash[i] = {};
  }
  for (const auto& lf : b.loads) {
    const int k = lf.facet.count();
    Vec3 p[3];
    for (int q = 0; q < k; ++q) p[q] = m.x[lf.facet.nodes[q]];
    const Vec3 av = face_area_vector(std::span<const Vec3>(p, k), k);  // outward, |av| = area
    if (lf.kind == 0) {
      const Vec3 fn = (-lf.a * b.tables[lf.table](t) / k) * av;  // pressure pushes inward
      for (int q = 0; q < k; ++q) {
        m.f[lf.facet.nodes[q]] += fn;
        b.f_load[lf.slot[q]] += fn;
      }
    } else {
      const double area = norm(av);
      const Vec3 n = av / area;
      for (int q = 0; q < k; ++q) {
        const auto nd = lf.facet.nodes[q];
        const Vec3 v = m.v[nd];
        const double vn = dot(v, n);
        const Vec3 fd = (-area / k) * (lf.a * vn * n + lf.b * (v - vn * n));
        m.f[nd] += fd;
        b.f_dash[lf.slot[q]] += fd;
      }
    }
  }
}

double apply_constraints(Model& m, Boundaries& b, double t, double dt) {
  double w = 0;
  for (const auto& c : b.constraints) {
    Vec3& v = m.v[c.node];
    const Vec3 vfree = v;
    switch (c.kind) {
      case 0: v = {}; break;
      case 1: v -= dot(v, c.dir) * c.dir; break;
      case 2: v = b.tables[c.table](t) * c.dir; break;
    }
    const Vec3 reaction = (m.mass[c.node] / dt) * (v - vfree);
    w += dot(reaction, 0.5 * (b.v_old[c.slot] + v)) * dt;
  }
  return w;
}

double load_work(const Model& m, const Boundaries& b, double dt, double* absorbed) {
  double w = 0, d = 0;
  for (std::size_t i = 0; i < b.work_nodes.size(); ++i) {
    const Vec3 vmid = 0.5 * (b.v_old[i] + m.v[b.work_nodes[i]]);
    w += dot(b.f_load[i], vmid) * dt;
    d -= dot(b.f_dash[i], vmid) * dt;
  }
  if (absorbed) *absorbed = d;
  return w;
}

}  // namespace cdem
