#include "cdem/mesh/topology.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <cmath>
#include <numeric>

#include "cdem/core/error.hpp"
#include "cdem/mesh/element_geometry.hpp"

namespace cdem {
namespace {

std::string join_names(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& n : v) s += (s.empty() ? "'" : ", '") + n + "'";
  return s;
}

// 2x2 Gauss points of the bilinear quad, shape functions N_i = (1 + xi xi_i)(1 + eta eta_i)/4.
constexpr double kXi[4] = {-1, 1, 1, -1};
constexpr double kEta[4] = {-1, -1, 1, 1};

void quad_reference_gradients(std::span<const Vec3> p, double* out) {
  const double g = 1.0 / std::sqrt(3.0);
  const double gp[4][2] = {{-g, -g}, {g, -g}, {g, g}, {-g, g}};
  for (int q = 0; q < 4; ++q) {
    double dNdxi[4], dNdeta[4];
    for (int i = 0; i < 4; ++i) {
      dNdxi[i] = 0.25 * kXi[i] * (1 + gp[q][1] * kEta[i]);
      dNdeta[i] = 0.25 * kEta[i] * (1 + gp[q][0] * kXi[i]);
    }
    double j00 = 0, j01 = 0, j10 = 0, j11 = 0;  // J = d(X,Y)/d(xi,eta)
    for (int i = 0; i < 4; ++i) {
      j00 += dNdxi[i] * p[i].x;
      j01 += dNdeta[i] * p[i].x;
      j10 += dNdxi[i] * p[i].y;
      j11 += dNdeta[i] * p[i].y;
    }
    const double detj = j00 * j11 - j01 * j10;
    double* o = out + 9 * q;
    o[0] = detj;  // Gauss weight 1 x detJ
    for (int i = 0; i < 4; ++i) {
      // grad_X N = J^-T grad_xi N
      o[1 + 2 * i] = (j11 * dNdxi[i] - j10 * dNdeta[i]) / detj;
      o[2 + 2 * i] = (-j01 * dNdxi[i] + j00 * dNdeta[i]) / detj;
    }
  }
}

}  // namespace

std::vector<FaceRec> sorted_faces(const Mesh& mesh, const std::vector<std::int32_t>& order) {
  std::vector<FaceRec> faces;
  faces.reserve(order.size() * 4);
  for (std::size_t b = 0; b < order.size(); ++b) {
    const auto e = order[b];
    const LocalFaces lf = local_faces(mesh.elem_type[e]);
    for (int k = 0; k < lf.count; ++k) {
      FaceRec r{{-1, -1, -1}, static_cast<std::int32_t>(b), static_cast<std::int8_t>(k)};
      for (int i = 0; i < lf.nodes_per_face; ++i) r.key[i] = mesh.elem_vertices[e][lf.f[k][i]];
      std::sort(r.key.begin(), r.key.begin() + lf.nodes_per_face);
      faces.push_back(r);
    }
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

Model build_model(const Mesh& mesh, const std::vector<BlockMaterial>& block_materials,
                  const std::vector<InterfaceMaterial>& iface_materials, const std::string& where) {
  Model m;
  m.dim = mesh.dim;
  m.springs_per_iface = mesh.dim == 2 ? 2 : 3;
  m.region_names = mesh.region_names;
  m.block_materials = block_materials;
  for (const auto& bm : block_materials) {
    m.mat_lambda.push_back(bm.lambda());
    m.mat_shear.push_back(bm.shear());
    m.mat_beta.push_back(bm.stiffness_damping);
  }

  // ---- region -> block material ----
  const std::size_t nreg = mesh.region_names.size();
  std::vector<int> region_mat(nreg, -1);
  for (std::size_t k = 0; k < block_materials.size(); ++k) {
    for (const auto& r : block_materials[k].regions) {
      const int ri = mesh.region_index(r);
      if (ri < 0)
        throw InputError(fmt::format("{}: material '{}': region '{}' is not in the mesh (its "
                                     "regions are {})",
                                     where, block_materials[k].name, r,
                                     join_names(mesh.region_names)));
      if (region_mat[ri] >= 0 && region_mat[ri] != static_cast<int>(k))
        throw InputError(fmt::format("{}: region '{}' is given two materials, '{}' and '{}'",
                                     where, r, block_materials[region_mat[ri]].name,
                                     block_materials[k].name));
      region_mat[ri] = static_cast<int>(k);
    }
  }
  std::vector<char> region_used(nreg, 0);
  for (auto r : mesh.elem_region) region_used[r] = 1;
  for (std::size_t r = 0; r < nreg; ++r)
    if (region_used[r] && region_mat[r] < 0)
      throw InputError(fmt::format("{}: region '{}' of the mesh has no [[material]] (add its name "
                                   "to some material's 'regions')",
                                   where, mesh.region_names[r]));

  // ---- block order: grouped by (type, kind), stable within a group ----
  const std::size_t ne = mesh.num_elements();
  auto kind_of = [&](std::size_t e) {
    return block_materials[region_mat[mesh.elem_region[e]]].explosive.empty() ? BlockKind::Elastic
                                                                               : BlockKind::Explosive;
  };
  std::vector<std::int32_t> order(ne);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    const auto ka = std::make_pair(static_cast<int>(kind_of(a)), static_cast<int>(mesh.elem_type[a]));
    const auto kb = std::make_pair(static_cast<int>(kind_of(b)), static_cast<int>(mesh.elem_type[b]));
    return ka < kb;
  });

  m.block_type.resize(ne);
  m.block_first_node.resize(ne + 1);
  m.block_region.resize(ne);
  m.block_material.resize(ne);
  m.block_elem_tag.resize(ne);
  m.block_volume0.resize(ne);
  m.block_size.resize(ne);
  m.block_altitude0.resize(ne);
  m.geom_offset.resize(ne + 1);
  std::int32_t nn = 0;
  std::int64_t ng = 0;
  for (std::size_t b = 0; b < ne; ++b) {
    const auto e = order[b];
    const ElemType t = mesh.elem_type[e];
    m.block_type[b] = t;
    m.block_first_node[b] = nn;
    nn += nodes_of(t);
    m.block_region[b] = mesh.elem_region[e];
    m.block_material[b] = region_mat[mesh.elem_region[e]];
    m.block_elem_tag[b] = static_cast<std::size_t>(e) < mesh.elem_tag.size() ? mesh.elem_tag[e] : static_cast<std::int64_t>(e + 1);
    m.geom_offset[b] = static_cast<std::int32_t>(ng);
    ng += t == ElemType::Tri3 ? 4 : (t == ElemType::Quad4 ? 36 : 9);
    if (b == 0 || t != m.block_type[b - 1] || kind_of(e) != kind_of(order[b - 1]))
      m.groups.push_back({t, kind_of(e), static_cast<std::int32_t>(b), 0});
    m.groups.back().end = static_cast<std::int32_t>(b + 1);
  }
  m.block_first_node[ne] = nn;
  if (ng > std::numeric_limits<std::int32_t>::max())
    throw MeshError(fmt::format("{}: {} elements are too many (the reference geometry needs more "
                                "than 2^31 numbers)", where, ne));
  m.geom_offset[ne] = static_cast<std::int32_t>(ng);
  m.geom.assign(static_cast<std::size_t>(ng), 0.0);

  // ---- split nodes, reference geometry, lumped masses ----
  m.vertex_X = mesh.vertices;
  m.node_vertex.resize(nn);
  m.mass.assign(nn, 0.0);
  m.damping.assign(nn, 0.0);
  m.local_damping.assign(nn, 0.0);
  for (std::size_t b = 0; b < ne; ++b) {
    const auto e = order[b];
    const int k = nodes_of(m.block_type[b]);
    std::array<Vec3, 4> p;
    for (int i = 0; i < k; ++i) {
      const auto vtx = mesh.elem_vertices[e][i];
      const auto n = m.block_first_node[b] + i;
      m.node_vertex[n] = vtx;
      p[i] = m.X(n);
    }
    const std::span<const Vec3> ps(p.data(), k);
    const double meas = signed_measure(m.block_type[b], ps);
    if (!(meas > 0))
      throw MeshError(fmt::format("{}: element {} ({}) has non-positive measure {:.3g}", where,
                                  m.block_elem_tag[b], name_of(m.block_type[b]), meas));
    m.block_volume0[b] = meas;
    m.block_size[b] = characteristic_size(m.block_type[b], meas);
    m.block_altitude0[b] = smallest_altitude(m.block_type[b], ps);
    double* g = m.geom.data() + m.geom_offset[b];
    const auto& mat = block_materials[m.block_material[b]];
    for (int i = 0; i < k; ++i) {
      const auto n = m.block_first_node[b] + i;
      m.mass[n] = mat.density * meas / k;  // tri rho A/3, quad rho A/4, tet rho V/4
      m.damping[n] = mat.damping;
      m.local_damping[n] = mat.local_damping;
    }
    switch (m.block_type[b]) {
      case ElemType::Tri3: {
        const double a = p[1].x - p[0].x, bb = p[2].x - p[0].x, c = p[1].y - p[0].y,
                     d = p[2].y - p[0].y;  // Dm = [[a, bb], [c, d]]
        const double det = a * d - bb * c;
        g[0] = d / det; g[1] = -bb / det; g[2] = -c / det; g[3] = a / det;
        break;
      }
      case ElemType::Quad4: quad_reference_gradients(ps, g); break;
      case ElemType::Tet4: {
        Mat3 dm;
        for (int j = 0; j < 3; ++j) {
          const Vec3 col = p[j + 1] - p[0];
          dm(0, j) = col.x; dm(1, j) = col.y; dm(2, j) = col.z;
        }
        const Mat3 inv = inverse(dm);
        for (int q = 0; q < 9; ++q) g[q] = inv.m[q];
        break;
      }
    }
  }
  m.inv_mass.resize(nn);
  for (std::int32_t n = 0; n < nn; ++n) m.inv_mass[n] = 1.0 / m.mass[n];
  m.x = m.X_nodes();
  m.v.assign(nn, Vec3{});
  m.f.assign(nn, Vec3{});
  m.stress.assign(ne, Sym6{});
  m.stress0.assign(ne, Sym6{});
  m.strain_energy.assign(ne, 0.0);
  m.vol_ratio.assign(ne, 1.0);

  // ---- faces: sort by vertex key, pairs become interfaces ----
  const std::vector<FaceRec> faces = sorted_faces(mesh, order);

  // Interface material lookup by region pair.
  m.iface_materials = iface_materials;
  int default_iface = -1;
  for (std::size_t k = 0; k < iface_materials.size(); ++k) {
    const auto& im = iface_materials[k];
    for (const auto& pr : im.pairs)
      for (const auto& r : {pr.first, pr.second})
        if (mesh.region_index(r) < 0)
          throw InputError(fmt::format("{}: interface '{}': region '{}' in 'pairs' is not in the mesh "
                                       "(its regions are {})",
                                       where, im.name, r, join_names(mesh.region_names)));
    if (im.is_default && default_iface >= 0 && iface_materials[default_iface].is_default)
      throw InputError(fmt::format("{}: interfaces '{}' and '{}' are both marked default = true; "
                                   "only one can be",
                                   where, iface_materials[default_iface].name, im.name));
    if (im.is_default || iface_materials.size() == 1) default_iface = static_cast<int>(k);
  }
  // Explosive blocks are joined to everything by unbreakable interfaces (SPEC 3).
  int explosive_iface = -1;
  auto iface_for = [&](std::int32_t ba, std::int32_t bb) -> int {
    const auto& ma = block_materials[m.block_material[ba]];
    const auto& mb = block_materials[m.block_material[bb]];
    if (!ma.explosive.empty() || !mb.explosive.empty()) {
      if (explosive_iface < 0) {
        InterfaceMaterial im;
        im.name = "explosive_contact";
        im.law = InterfaceLaw::Elastic;
        m.iface_materials.push_back(im);
        explosive_iface = static_cast<int>(m.iface_materials.size() - 1);
      }
      return explosive_iface;
    }
    const auto& ra = mesh.region_names[m.block_region[ba]];
    const auto& rb = mesh.region_names[m.block_region[bb]];
    for (std::size_t k = 0; k < iface_materials.size(); ++k)
      for (const auto& pr : iface_materials[k].pairs)
        if ((pr.first == ra && pr.second == rb) || (pr.first == rb && pr.second == ra))
          return static_cast<int>(k);
    if (default_iface >= 0) return default_iface;
    throw InputError(fmt::format("{}: no [[interface]] material for the region pair ('{}', '{}'); "
                                 "list it in some interface's 'pairs' or mark one 'default = true'",
                                 where, ra, rb));
  };

  const int np = m.springs_per_iface;
  struct FaceRef { std::int32_t block; std::int8_t local; bool paired; };
  // Boundary lookup for face sets: key -> the owning (first) block face.
  std::vector<std::pair<std::array<std::int32_t, 3>, FaceRef>> face_index;
  face_index.reserve(faces.size());
  std::vector<double> iface_area0;  // reference face areas (m^2; 2D: length x 1 m), per interface
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2)
      throw MeshError(fmt::format("{}: non-manifold mesh: a face is shared by {} elements "
                                  "(elements {} and {} among them)",
                                  where, j - i, m.block_elem_tag[faces[i].block],
                                  m.block_elem_tag[faces[i + 1].block]));
    face_index.push_back({faces[i].key, {faces[i].block, faces[i].local, j - i == 2}});
    if (j - i == 2) {
      const auto ba = faces[i].block, bb = faces[i + 1].block;
      const LocalFaces lf = local_faces(m.block_type[ba]);
      const auto& loc = lf.f[faces[i].local];
      const int ki = iface_for(ba, bb);
      m.iface_block_a.push_back(ba);
      m.iface_block_b.push_back(bb);
      m.iface_material.push_back(ki);
      std::array<Vec3, 3> fp;
      for (int q = 0; q < np; ++q) {
        const auto na = m.block_first_node[ba] + loc[q];
        std::int32_t nb = -1;
        for (auto n = m.block_first_node[bb]; n < m.block_first_node[bb + 1]; ++n)
          if (m.node_vertex[n] == m.node_vertex[na]) nb = n;
        m.sp_a.push_back(na);
        m.sp_b.push_back(nb);
        fp[q] = m.X(na);
      }
      const double area = norm(face_area_vector(std::span<const Vec3>(fp.data(), np), np));
      iface_area0.push_back(area);
    }
    i = j;
  }
  // Interfaces in block order (by the pair of block indices) instead of the faces' vertex-key
  // order: the spring kernel's gathers of node positions and velocities and the blocks' spring
  // gather then walk the node and interface arrays nearly in sequence (locality).
  {
    const std::size_t ni = m.iface_block_a.size();
    std::vector<std::int32_t> perm(ni);
    std::iota(perm.begin(), perm.end(), 0);
    auto lo = [&m](std::int32_t i) { return std::min(m.iface_block_a[i], m.iface_block_b[i]); };
    auto hi = [&m](std::int32_t i) { return std::max(m.iface_block_a[i], m.iface_block_b[i]); };
    std::stable_sort(perm.begin(), perm.end(), [&](std::int32_t p, std::int32_t q) {
      return lo(p) != lo(q) ? lo(p) < lo(q) : hi(p) < hi(q);
    });
    auto permute = [&perm](auto& v, int per) {
      auto out = v;
      for (std::size_t k = 0; k < perm.size(); ++k)
        for (int q = 0; q < per; ++q) out[k * per + q] = v[static_cast<std::size_t>(perm[k]) * per + q];
      v.swap(out);
    };
    permute(m.iface_block_a, 1);
    permute(m.iface_block_b, 1);
    permute(m.iface_material, 1);
    permute(iface_area0, 1);
    permute(m.sp_a, np);
    permute(m.sp_b, np);
  }

  // ---- spring point parameters (SPEC 1.3) ----
  const std::size_t ns = m.sp_a.size();
  for (auto* c : {&m.sp_area, &m.sp_kn, &m.sp_ks}) {
    c->v.assign(m.n_ifaces(), 0.0);
    c->per = np;
  }
  m.sp_fn.assign(ns, 0.0);
  m.sp_fs.assign(ns, Vec3{});
  m.sp_w.assign(ns, 0.0);
  m.sp_slip.assign(ns, 0.0);
  m.sp_dil.assign(ns, 0.0);
  m.sp_state.assign(ns, kIntact);
  m.sp_mode.assign(ns, kModeNone);
  m.sp_break_time.assign(ns, -1.0f);
  m.sp_dissipated.assign(ns, 0.0);
  m.iface_normal.assign(m.n_ifaces(), Vec3{});
  m.iface_normal_set = false;
  for (const auto& im : m.iface_materials) m.spring_laws.push_back(make_spring_law(im));
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    const auto ba = m.iface_block_a[i], bb = m.iface_block_b[i];
    const auto& ma = block_materials[m.block_material[ba]];
    const auto& mb = block_materials[m.block_material[bb]];
    // The softer elastic side sets the stiffness (explosive blocks carry no shear: use the rock).
    const BlockMaterial* soft = nullptr;
    for (const auto* mm : {&ma, &mb})
      if (mm->explosive.empty() && (!soft || mm->youngs < soft->youngs)) soft = mm;
    if (!soft) soft = ma.youngs <= mb.youngs ? &ma : &mb;
    const auto& im = m.iface_materials[m.iface_material[i]];
    const double h = 0.5 * (m.block_size[ba] + m.block_size[bb]);
    const double kn = im.stiffness_factor * soft->youngs / h;  // Pa/m
    const double ks = kn * soft->shear() / soft->youngs;
    const double ac = iface_area0[i] / np;
    m.sp_area.v[i] = ac;
    m.sp_kn.v[i] = kn * ac;
    m.sp_ks.v[i] = ks * ac;
    for (int q = 0; q < np; ++q) {
      const auto s = i * np + q;
      if (im.precracked) m.sp_state[s] = kBroken;
    }
  }

  // ---- block -> interface CSR, ascending interface (the gather's fixed order) ----
  m.block_iface_offset.assign(ne + 1, 0);
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    ++m.block_iface_offset[m.iface_block_a[i] + 1];
    ++m.block_iface_offset[m.iface_block_b[i] + 1];
  }
  for (std::size_t b = 0; b < ne; ++b) m.block_iface_offset[b + 1] += m.block_iface_offset[b];
  m.block_iface_list.resize(2 * m.n_ifaces());
  {
    std::vector<std::int32_t> fill(m.block_iface_offset.begin(), m.block_iface_offset.end() - 1);
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      m.block_iface_list[fill[m.iface_block_a[i]]++] = static_cast<std::int32_t>(i + 1);
      m.block_iface_list[fill[m.iface_block_b[i]]++] = -static_cast<std::int32_t>(i + 1);
    }
  }

  // ---- face sets -> boundary facets on block nodes ----
  for (const auto& fs : mesh.face_sets) {
    Model::FacetSet out;
    out.name = fs.name;
    for (const auto& fc : fs.facets) {
      std::array<std::int32_t, 3> key = fc.v;
      const int k = fc.count();
      std::sort(key.begin(), key.begin() + k);
      auto it = std::lower_bound(face_index.begin(), face_index.end(), key,
                                 [](const auto& a, const auto& kk) { return a.first < kk; });
      if (it == face_index.end() || it->first != key)
        throw MeshError(fmt::format("{}: face set '{}': a facet (vertices {}, {}{}) is not a face "
                                    "of any element",
                                    where, fs.name, fc.v[0], fc.v[1],
                                    k == 3 ? fmt::format(", {}", fc.v[2]) : std::string()));
      const auto b = it->second.block;
      const auto loc = local_faces(m.block_type[b]).f[it->second.local];
      Model::BoundaryFacet bf;
      bf.block = b;
      for (int q = 0; q < k; ++q) bf.nodes[q] = m.block_first_node[b] + loc[q];
      out.facets.push_back(bf);
    }
    m.facet_sets.push_back(std::move(out));
  }
  return m;
}

}  // namespace cdem
