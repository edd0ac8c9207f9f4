// Assembly of a RawModel into a Mesh: the rules of read_gmsh (gmsh_io.hpp) in one place, for
// mesh files (msh_reader.cpp) and generated meshes (the Gmsh model, gmsh_io.cpp) alike.
#include "cdem/mesh/mesh_assembly.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "cdem/core/error.hpp"
#include "cdem/mesh/gmsh_io.hpp"
#include "cdem/mesh/msh_element_types.hpp"

namespace cdem {
namespace {

std::string type_name(int type) {
  const MshElementType* t = msh_element_type(type);
  return t ? t->name : fmt::format("type {}", type);
}

int type_dim(int type) {
  const MshElementType* t = msh_element_type(type);
  return t ? t->dim : -1;
}

int type_nodes(int type) {
  const MshElementType* t = msh_element_type(type);
  return t ? t->nodes : 0;
}

}  // namespace

Mesh assemble_mesh(const RawModel& raw, const std::string& source) {
  auto fail = [&](const std::string& what) -> void {
    throw MeshError(fmt::format("{}: {}", source, what));
  };
  // " (line 30)" for an element or node whose offset is known, else "".
  auto at = [&](const std::vector<std::uint64_t>& offsets, std::size_t i) -> std::string {
    if (!raw.locate || i >= offsets.size()) return "";
    return fmt::format(" ({})", raw.locate(offsets[i]));
  };

  // " (at A and at B)" for two items whose offsets are known.
  auto both = [&](const std::vector<std::uint64_t>& oa, std::size_t a,
                  const std::vector<std::uint64_t>& ob, std::size_t b) -> std::string {
    if (!raw.locate || a >= oa.size() || b >= ob.size()) return "";
    return fmt::format(" (at {} and at {})", raw.locate(oa[a]), raw.locate(ob[b]));
  };

  // Structure of the blocks (a RawModel from the reader is consistent; this guards the rules
  // below against any other producer).
  int top = -1;
  for (const RawElementBlock& b : raw.blocks) {
    const int nn = type_nodes(b.type);
    if (nn <= 0 || type_dim(b.type) < 0)
      fail(fmt::format("element type {} is not a known fixed-size Gmsh element type", b.type));
    if (b.nodes.size() != b.tags.size() * static_cast<std::size_t>(nn))
      fail(fmt::format("element block of type '{}': {} node tags for {} elements",
                       type_name(b.type), b.nodes.size(), b.tags.size()));
    if (!b.tags.empty()) top = std::max(top, type_dim(b.type));
  }
  if (top < 2)
    fail("no 2D or 3D elements (a mesh file must contain the mesh, not only the geometry)");

  // Element types: linear triangles and quadrangles (2D), linear tetrahedra (3D), their
  // boundary lines / triangles, points. Anything else (second order, hexahedra, ...) is refused.
  // The blocks of the top dimension are looked at first: a mesh of hexahedra is reported as
  // hexahedra, not as the quadrilaterals on its boundary.
  const int facet_type = top == 2 ? 1 : 2;
  auto supported = [&](int type) {
    return top == 2 ? (type == 2 || type == 3 || type == 1 || type == 15)
                    : (type == 4 || type == 2 || type == 1 || type == 15);
  };
  for (int pass = 0; pass < 2; ++pass)
    for (const RawElementBlock& b : raw.blocks) {
      if (b.tags.empty() || (type_dim(b.type) == top) != (pass == 0)) continue;
      if (!supported(b.type))
        fail(fmt::format(
            "element {}{}: unsupported element type '{}' (Gmsh type {}); cdemblast takes "
            "linear elements only: 3-node triangles and 4-node quadrilaterals in 2D, 4-node "
            "tetrahedra in 3D, with 2-node lines, 3-node triangles and points on boundaries",
            b.tags.front(), at(b.offsets, 0), type_name(b.type), b.type));
    }
  auto is_top = [&](const RawElementBlock& b) { return type_dim(b.type) == top; };

  Mesh mesh;
  mesh.dim = top;
  auto group_name = [](const RawPhysicalGroup& g) {
    return g.name.empty() ? std::to_string(g.tag) : g.name;
  };

  // Regions: physical groups of the top dimension, by increasing tag; the first group holding
  // an entity gets its elements; groups of the same name are one region.
  std::map<int, int> entity_region;  // top-dim entity tag -> region index
  std::vector<int> region_group;     // a physical group tag of each region (for messages)
  auto region_of_name = [&](const std::string& name, int group) {
    int r = mesh.region_index(name);
    if (r < 0) {
      r = static_cast<int>(mesh.region_names.size());
      mesh.region_names.push_back(name);
      region_group.push_back(group);
    }
    return r;
  };
  for (const RawPhysicalGroup& g : raw.groups) {
    if (g.dim != top) continue;
    const int r = region_of_name(group_name(g), g.tag);
    for (int e : g.entities) entity_region.emplace(e, r);  // keeps the first group
  }

  // Top-dimension elements, sorted by element tag (the file's numbering).
  struct Elem {
    std::uint64_t tag;
    ElemType type;
    std::array<std::uint64_t, 4> nodes;
    int region;
    const RawElementBlock* block;
    std::size_t index;  // in its block
  };
  std::vector<Elem> elems;
  {
    std::size_t n = 0;
    for (const RawElementBlock& b : raw.blocks)
      if (is_top(b)) n += b.tags.size();
    elems.reserve(n);
  }
  int default_region = -1;
  for (const RawElementBlock& b : raw.blocks) {
    if (!is_top(b) || b.tags.empty()) continue;
    int r;
    if (auto it = entity_region.find(b.entity_tag); it != entity_region.end()) {
      r = it->second;
    } else {
      if (default_region < 0) default_region = region_of_name("default", -1);
      r = default_region;
    }
    const ElemType t =
        b.type == 2 ? ElemType::Tri3 : (b.type == 3 ? ElemType::Quad4 : ElemType::Tet4);
    const std::size_t nn = static_cast<std::size_t>(nodes_of(t));
    for (std::size_t i = 0; i < b.tags.size(); ++i) {
      Elem e{b.tags[i], t, {0, 0, 0, 0}, r, &b, i};
      for (std::size_t k = 0; k < nn; ++k) e.nodes[k] = b.nodes[i * nn + k];
      elems.push_back(e);
    }
  }
  std::stable_sort(elems.begin(), elems.end(),
                   [](const Elem& a, const Elem& b) { return a.tag < b.tag; });
  for (std::size_t i = 1; i < elems.size(); ++i)
    if (elems[i].tag == elems[i - 1].tag)
      fail(fmt::format("element tag {} is used twice{} (element tags must be unique)", elems[i].tag,
                       both(elems[i - 1].block->offsets, elems[i - 1].index,
                            elems[i].block->offsets, elems[i].index)));
  if (elems.size() > static_cast<std::size_t>(INT32_MAX))
    fail(fmt::format("{} elements are more than cdemblast can index", elems.size()));

  // Every region has elements.
  std::vector<std::size_t> region_count(mesh.region_names.size(), 0);
  for (const Elem& e : elems) ++region_count[static_cast<std::size_t>(e.region)];
  for (std::size_t r = 0; r < region_count.size(); ++r)
    if (region_count[r] == 0)
      fail(fmt::format("region '{}' (physical group {} of dimension {}) has no elements{}",
                       mesh.region_names[r], region_group[r], top,
                       " (or all of them belong to an earlier physical group)"));

  // The nodes by tag: every tag defined once.
  std::vector<std::size_t> by_tag(raw.node_tags.size());
  std::iota(by_tag.begin(), by_tag.end(), std::size_t{0});
  std::stable_sort(by_tag.begin(), by_tag.end(), [&](std::size_t a, std::size_t b) {
    return raw.node_tags[a] < raw.node_tags[b];
  });
  for (std::size_t i = 1; i < by_tag.size(); ++i)
    if (raw.node_tags[by_tag[i]] == raw.node_tags[by_tag[i - 1]])
      fail(fmt::format("node tag {} is defined twice{} (node tags must be unique)",
                       raw.node_tags[by_tag[i]],
                       both(raw.node_offsets, by_tag[i - 1], raw.node_offsets, by_tag[i])));
  // Index of the node with this tag, or SIZE_MAX.
  auto find_node = [&](std::uint64_t tag) -> std::size_t {
    auto it =
        std::lower_bound(by_tag.begin(), by_tag.end(), tag,
                         [&](std::size_t i, std::uint64_t t) { return raw.node_tags[i] < t; });
    return it != by_tag.end() && raw.node_tags[*it] == tag ? *it : SIZE_MAX;
  };

  // Vertices: the nodes of the elements, numbered 0..n-1 in increasing node tag order.
  std::vector<std::uint64_t> used;
  used.reserve(elems.size() * 4);
  for (const Elem& e : elems)
    for (int k = 0; k < nodes_of(e.type); ++k) {
      const std::uint64_t node = e.nodes[static_cast<std::size_t>(k)];
      if (find_node(node) == SIZE_MAX)
        fail(fmt::format("element {}{}: node {} is not defined (no such tag in $Nodes)", e.tag,
                         at(e.block->offsets, e.index), node));
      used.push_back(node);
    }
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  if (used.size() > static_cast<std::size_t>(INT32_MAX))
    fail(fmt::format("{} vertices are more than cdemblast can index", used.size()));
  std::unordered_map<std::uint64_t, std::int32_t> vertex_of;
  vertex_of.reserve(used.size());
  mesh.vertices.resize(used.size());
  for (std::size_t i = 0; i < used.size(); ++i) {
    vertex_of.emplace(used[i], static_cast<std::int32_t>(i));
    mesh.vertices[i] = raw.node_coords[find_node(used[i])];
  }

  const std::size_t ne = elems.size();
  mesh.elem_type.resize(ne);
  mesh.elem_vertices.resize(ne);
  mesh.elem_region.resize(ne);
  mesh.elem_tag.resize(ne);
  for (std::size_t i = 0; i < ne; ++i) {
    const Elem& e = elems[i];
    mesh.elem_type[i] = e.type;
    std::array<std::int32_t, 4> v{-1, -1, -1, -1};
    for (int k = 0; k < nodes_of(e.type); ++k)
      v[static_cast<std::size_t>(k)] = vertex_of.at(e.nodes[static_cast<std::size_t>(k)]);
    mesh.elem_vertices[i] = v;
    mesh.elem_region[i] = e.region;
    mesh.elem_tag[i] = static_cast<std::int64_t>(e.tag);
  }

  // Face sets: physical groups of dimension top - 1; facets sorted by element tag.
  for (const RawPhysicalGroup& g : raw.groups) {
    if (g.dim == 0) {
      const std::string name = group_name(g);
      if (std::find(mesh.point_names.begin(), mesh.point_names.end(), name) ==
          mesh.point_names.end())
        mesh.point_names.push_back(name);
    }
    if (g.dim != top - 1) continue;
    const std::string name = group_name(g);
    std::vector<std::pair<std::uint64_t, Facet>> facets;
    for (const RawElementBlock& b : raw.blocks) {
      if (b.entity_dim != g.dim || b.tags.empty() ||
          std::find(g.entities.begin(), g.entities.end(), b.entity_tag) == g.entities.end())
        continue;
      if (b.type != facet_type)
        fail(fmt::format(
            "element {}{}: a '{}' in face set '{}' (physical group {} of dimension {}); {} face "
            "sets take {} only",
            b.tags.front(), at(b.offsets, 0), type_name(b.type), name, g.tag, g.dim,
            top == 2 ? "2D" : "3D", top == 2 ? "2-node lines" : "3-node triangles"));
      const std::size_t nn = static_cast<std::size_t>(type_nodes(b.type));
      for (std::size_t i = 0; i < b.tags.size(); ++i) {
        Facet f;
        for (std::size_t k = 0; k < nn; ++k) {
          const std::uint64_t node = b.nodes[i * nn + k];
          auto it = vertex_of.find(node);
          if (it == vertex_of.end())
            fail(fmt::format(
                "element {}{} of face set '{}': node {} is not a vertex of any {}D element (a "
                "face set must lie on the mesh)",
                b.tags[i], at(b.offsets, i), name, node, top));
          f.v[k] = it->second;
        }
        facets.emplace_back(b.tags[i], f);
      }
    }
    std::stable_sort(facets.begin(), facets.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    FaceSet* fs = nullptr;
    for (FaceSet& other : mesh.face_sets)
      if (other.name == name) fs = &other;
    if (fs == nullptr) {
      mesh.face_sets.push_back(FaceSet{name, {}});
      fs = &mesh.face_sets.back();
    }
    for (const auto& tf : facets) fs->facets.push_back(tf.second);
  }
  for (const FaceSet& fs : mesh.face_sets)
    if (fs.facets.empty())
      fail(fmt::format("face set '{}' (physical group of dimension {}) has no elements", fs.name,
                       top - 1));

  check_mesh(mesh, source);
  return mesh;
}

}  // namespace cdem
