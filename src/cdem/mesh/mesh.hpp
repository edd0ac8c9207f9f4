// The input mesh as read from Gmsh or generated: shared vertices, elements, regions, face sets.
// This is the geometric description before the CDEM split (see mesh/topology.hpp).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

enum class ElemType : std::uint8_t { Tri3 = 0, Quad4 = 1, Tet4 = 2 };
constexpr int nodes_of(ElemType t) { return t == ElemType::Tri3 ? 3 : 4; }
constexpr const char* name_of(ElemType t) {
  return t == ElemType::Tri3 ? "triangle" : (t == ElemType::Quad4 ? "quadrilateral" : "tetrahedron");
}

// A boundary facet: a 2-node edge (2D) or a 3-node triangle (3D); unused slots are -1.
struct Facet {
  std::array<std::int32_t, 3> v{-1, -1, -1};
  int count() const { return v[2] < 0 ? 2 : 3; }
};

struct FaceSet {
  std::string name;
  std::vector<Facet> facets;
};

struct Mesh {
  int dim = 0;                          // 2 (plane strain, z = 0) or 3
  std::vector<Vec3> vertices;           // shared mesh vertices
  std::vector<ElemType> elem_type;      // per element
  std::vector<std::array<std::int32_t, 4>> elem_vertices;  // unused slot = -1 (triangles)
  std::vector<std::int32_t> elem_region;                   // index into region_names
  std::vector<std::int64_t> elem_tag;   // the element's number in the source file (for messages)
  std::vector<std::string> region_names;  // physical group names of dimension dim
  std::vector<FaceSet> face_sets;         // physical groups of dimension dim - 1
  std::vector<std::string> point_names;   // physical groups of dimension 0 (unused by the solver)

  std::size_t num_elements() const { return elem_type.size(); }
  int region_index(const std::string& name) const {
    for (std::size_t i = 0; i < region_names.size(); ++i)
      if (region_names[i] == name) return static_cast<int>(i);
    return -1;
  }
  const FaceSet* face_set(const std::string& name) const {
    for (const auto& f : face_sets)
      if (f.name == name) return &f;
    return nullptr;
  }
};

}  // namespace cdem
