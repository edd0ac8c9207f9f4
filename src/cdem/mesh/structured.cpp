#include "cdem/mesh/structured.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "cdem/mesh/element_geometry.hpp"

namespace cdem {

void add_box_face_sets(Mesh& mesh) {
  struct Rec {
    std::array<std::int32_t, 3> key;
    Facet facet;
  };
  std::vector<Rec> recs;
  recs.reserve(mesh.num_elements() * 4);
  for (std::size_t e = 0; e < mesh.num_elements(); ++e) {
    const LocalFaces lf = local_faces(mesh.elem_type[e]);
    for (int k = 0; k < lf.count; ++k) {
      Rec r;
      for (int i = 0; i < lf.nodes_per_face; ++i) r.facet.v[i] = mesh.elem_vertices[e][lf.f[k][i]];
      r.key = r.facet.v;
      std::sort(r.key.begin(), r.key.begin() + lf.nodes_per_face);
      recs.push_back(r);
    }
  }
  std::sort(recs.begin(), recs.end(), [](const Rec& a, const Rec& b) { return a.key < b.key; });
  std::vector<Facet> outer;
  for (std::size_t i = 0; i < recs.size();) {
    std::size_t j = i + 1;
    while (j < recs.size() && recs[j].key == recs[i].key) ++j;
    if (j - i == 1) outer.push_back(recs[i].facet);
    i = j;
  }
  Vec3 lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const auto& p : mesh.vertices)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  struct Side {
    const char* name;
    int axis;
    double value;
  };
  std::vector<Side> sides;
  if (mesh.dim == 2)
    sides = {{"left", 0, lo.x}, {"right", 0, hi.x}, {"bottom", 1, lo.y}, {"top", 1, hi.y}};
  else
    sides = {{"left", 0, lo.x}, {"right", 0, hi.x},  {"front", 1, lo.y},
             {"back", 1, hi.y}, {"bottom", 2, lo.z}, {"top", 2, hi.z}};
  const double tol = 1e-12 * (norm(hi - lo) + 1.0);
  for (const auto& s : sides) {
    FaceSet fs;
    fs.name = s.name;
    for (const auto& f : outer) {
      bool on = true;
      for (int i = 0; i < f.count(); ++i)
        on = on && std::abs(mesh.vertices[f.v[i]][s.axis] - s.value) <= tol;
      if (on) fs.facets.push_back(f);
    }
    mesh.face_sets.push_back(std::move(fs));
  }
}

Mesh structured_grid_2d(int nx, int ny, double h, bool quads) {
  Mesh m;
  m.dim = 2;
  m.region_names = {"rock"};
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.vertices.push_back({h * i, h * j, 0.0});
  auto vid = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  auto add = [&](ElemType t, std::array<std::int32_t, 4> v) {
    m.elem_type.push_back(t);
    m.elem_vertices.push_back(v);
    m.elem_region.push_back(0);
    m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (quads) {
        add(ElemType::Quad4, {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)});
      } else {
        add(ElemType::Tri3, {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), -1});
        add(ElemType::Tri3, {vid(i, j), vid(i + 1, j + 1), vid(i, j + 1), -1});
      }
    }
  add_box_face_sets(m);
  return m;
}

Mesh structured_tet_box(int nx, int ny, int nz, Vec3 size, Vec3 origin, const std::string& region) {
  Mesh m;
  m.dim = 3;
  m.region_names = {region};
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        m.vertices.push_back(
            {origin.x + size.x * i / nx, origin.y + size.y * j / ny, origin.z + size.z * k / nz});
  auto vid = [&](int i, int j, int k) {
    return static_cast<std::int32_t>((k * (ny + 1) + j) * (nx + 1) + i);
  };
  const std::array<std::array<int, 3>, 6> perms{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> c{i, j, k};
          std::array<std::int32_t, 4> t{};
          t[0] = vid(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = vid(c[0], c[1], c[2]);
          }
          const Vec3 a = m.vertices[t[0]], b = m.vertices[t[1]], cc = m.vertices[t[2]],
                     d = m.vertices[t[3]];
          if (dot(b - a, cross(cc - a, d - a)) < 0) std::swap(t[1], t[2]);
          m.elem_type.push_back(ElemType::Tet4);
          m.elem_vertices.push_back(t);
          m.elem_region.push_back(0);
          m.elem_tag.push_back(static_cast<std::int64_t>(m.elem_tag.size() + 1));
        }
  add_box_face_sets(m);
  return m;
}

}  // namespace cdem
