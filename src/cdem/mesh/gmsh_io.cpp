// Gmsh front end, reading and writing: the Gmsh session guard, the extraction of a Mesh from
// the in-memory Gmsh model (shared with generate_mesh), read_gmsh and write_gmsh.
// Gmsh 4.8 C++ API (gmsh.h); element type numbers are those of the MSH format
// (1 line, 2 triangle, 3 quadrangle, 4 tetrahedron, 15 point).
#include "cdem/mesh/gmsh_io.hpp"

#include <fmt/format.h>
#include <gmsh.h>
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <unordered_map>
#include <utility>

#include "cdem/core/error.hpp"

namespace cdem {

// ---------------------------------------------------------------------------------------------
// Session guard

namespace {

// Gmsh is a process-wide singleton: one recursive mutex serialises its use; the depth counts
// the sessions the owning thread has open (only touched with the mutex held).
std::recursive_mutex& gmsh_mutex() {
  static std::recursive_mutex m;
  return m;
}
int g_session_depth = 0;
int g_nested_models = 0;
// OpenMP threads of the caller before the outermost session: Gmsh's General.NumThreads = 1
// calls omp_set_num_threads(1), which would leave every later parallel region of the run on
// one thread; the outermost session restores the caller's setting when it ends.
int g_caller_threads = 0;

}  // namespace

GmshSession::GmshSession(std::string context) : context_(std::move(context)) {
  gmsh_mutex().lock();
  try {
    if (g_session_depth == 0) {
      g_caller_threads = omp_get_max_threads();
      // No configuration files (reproducible), no terminal output, one thread (reproducible
      // meshes); errors throw (General.AbortOnError = 2 is set by initialize).
      gmsh::initialize(0, nullptr, false);
      ++g_session_depth;
      gmsh::option::setNumber("General.Terminal", 0);
      gmsh::option::setNumber("General.NumThreads", 1);
      gmsh::logger::start();
    } else {
      ++g_session_depth;
      nested_ = true;
      gmsh::model::getCurrent(outer_model_);
      gmsh::model::add(fmt::format("cdem_nested_{}", ++g_nested_models));
      std::vector<std::string> log;
      gmsh::logger::get(log);
      log_seen_ = log.size();
    }
  } catch (...) {
    if (g_session_depth > 0 && !nested_) {
      try {
        gmsh::finalize();
      } catch (...) {
      }
      if (g_caller_threads > 0) omp_set_num_threads(g_caller_threads);
    }
    if (g_session_depth > 0) --g_session_depth;
    gmsh_mutex().unlock();
    try {
      throw;
    } catch (const std::string& s) {
      throw MeshError(fmt::format("{}: cannot start gmsh: {}", context_, s));
    } catch (const std::exception& e) {
      throw MeshError(fmt::format("{}: cannot start gmsh: {}", context_, e.what()));
    }
  }
}

GmshSession::~GmshSession() {
  // Destructors must not throw: Gmsh errors at clean-up are ignored.
  try {
    if (nested_) {
      gmsh::model::remove();
      gmsh::model::setCurrent(outer_model_);
    } else {
      gmsh::logger::stop();
      gmsh::finalize();
    }
  } catch (...) {
  }
  if (!nested_ && g_caller_threads > 0) omp_set_num_threads(g_caller_threads);
  --g_session_depth;
  gmsh_mutex().unlock();
}

void GmshSession::check_log() {
  std::vector<std::string> log;
  gmsh::logger::get(log);
  std::string first_error;
  for (std::size_t i = log_seen_; i < log.size(); ++i) {
    const std::string& line = log[i];
    if (line.rfind("Error", 0) == 0) {
      if (first_error.empty()) first_error = line;
    } else if (line.find("I'm busy! Ask me that later") != std::string::npos) {
      // Gmsh stays locked after an error inside gmsh::open until it is finalized: only an
      // outermost session can reset it.
      if (first_error.empty())
        first_error =
            "Gmsh is locked by an earlier error in this session (it did not read the file); "
            "use Gmsh from an outermost GmshSession";
    } else if (line.rfind("Warning", 0) == 0) {
      spdlog::warn("{}: gmsh: {}", context_, line);
    } else {
      spdlog::debug("{}: gmsh: {}", context_, line);
    }
  }
  log_seen_ = log.size();
  if (!first_error.empty()) throw MeshError(fmt::format("{}: gmsh: {}", context_, first_error));
}

void GmshSession::rethrow_as_mesh_error() {
  try {
    throw;
  } catch (const MeshError&) {
    throw;
  } catch (const std::string& s) {  // Gmsh 4.8 throws its error message as a std::string
    throw MeshError(fmt::format("{}: gmsh: {}", context_, s));
  } catch (const char* s) {
    throw MeshError(fmt::format("{}: gmsh: {}", context_, s));
  } catch (const std::exception& e) {
    throw MeshError(fmt::format("{}: {}", context_, e.what()));
  } catch (...) {
    throw MeshError(fmt::format("{}: unknown error in gmsh", context_));
  }
}

// ---------------------------------------------------------------------------------------------
// Extraction of the current Gmsh model

namespace {

struct TypeInfo {
  std::string name;
  int dim = 0;
  int num_nodes = 0;
};

// Elements of one type on one model entity, as Gmsh returns them.
struct Block {
  int entity_dim = 0;
  int entity_tag = 0;
  int type = 0;
  const TypeInfo* info = nullptr;
  std::vector<std::size_t> tags;
  std::vector<std::size_t> nodes;  // num_nodes per element
};

std::string group_name(int dim, int tag) {
  std::string name;
  gmsh::model::getPhysicalName(dim, tag, name);
  return name.empty() ? std::to_string(tag) : name;
}

}  // namespace

Mesh detail::extract_gmsh_model(const std::string& source) {
  auto fail = [&](const std::string& what) -> void {
    throw MeshError(fmt::format("{}: {}", source, what));
  };

  // All elements, entity by entity.
  std::map<int, TypeInfo> types;
  std::vector<Block> blocks;
  int top = -1;
  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities);
  for (const auto& [edim, etag] : entities) {
    std::vector<int> etypes;
    std::vector<std::vector<std::size_t>> etags, enodes;
    gmsh::model::mesh::getElements(etypes, etags, enodes, edim, etag);
    for (std::size_t i = 0; i < etypes.size(); ++i) {
      if (etags[i].empty()) continue;
      auto it = types.find(etypes[i]);
      if (it == types.end()) {
        TypeInfo ti;
        int order = 0, primary = 0;
        std::vector<double> local;
        gmsh::model::mesh::getElementProperties(etypes[i], ti.name, ti.dim, order, ti.num_nodes,
                                                local, primary);
        it = types.emplace(etypes[i], ti).first;
      }
      Block b;
      b.entity_dim = edim;
      b.entity_tag = etag;
      b.type = etypes[i];
      b.info = &it->second;
      b.tags = std::move(etags[i]);
      b.nodes = std::move(enodes[i]);
      top = std::max(top, b.info->dim);
      blocks.push_back(std::move(b));
    }
  }
  if (top < 2)
    fail("no 2D or 3D elements (a mesh file must contain the mesh, not only the geometry)");

  // Element types: linear triangles and quadrangles (2D), linear tetrahedra (3D), their
  // boundary lines / triangles, points. Anything else (second order, hexahedra, ...) is refused.
  const int facet_type = top == 2 ? 1 : 2;
  for (const Block& b : blocks) {
    const bool ok = top == 2 ? (b.type == 2 || b.type == 3 || b.type == 1 || b.type == 15)
                             : (b.type == 4 || b.type == 2 || b.type == 1 || b.type == 15);
    if (!ok)
      fail(fmt::format(
          "element {}: unsupported element type '{}' (Gmsh type {}); cdemblast takes "
          "linear elements only: 3-node triangles and 4-node quadrilaterals in 2D, 4-node "
          "tetrahedra in 3D, with 2-node lines, 3-node triangles and points on boundaries",
          b.tags.front(), b.info->name, b.type));
  }
  auto is_top = [&](const Block& b) { return b.info->dim == top; };

  Mesh mesh;
  mesh.dim = top;

  // Regions: physical groups of the top dimension, by increasing tag; the first group holding
  // an entity gets its elements; groups of the same name are one region.
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups);
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
  for (const auto& [gdim, gtag] : groups) {
    if (gdim != top) continue;
    const int r = region_of_name(group_name(gdim, gtag), gtag);
    std::vector<int> ents;
    gmsh::model::getEntitiesForPhysicalGroup(gdim, gtag, ents);
    for (int e : ents) entity_region.emplace(e, r);  // keeps the first group
  }

  // Top-dimension elements, sorted by element tag (the file's numbering).
  struct Elem {
    std::size_t tag;
    ElemType type;
    std::array<std::size_t, 4> nodes;
    int region;
  };
  std::vector<Elem> elems;
  int default_region = -1;
  for (const Block& b : blocks) {
    if (!is_top(b)) continue;
    int r;
    if (auto it = entity_region.find(b.entity_tag); it != entity_region.end()) {
      r = it->second;
    } else {
      if (default_region < 0) default_region = region_of_name("default", -1);
      r = default_region;
    }
    const ElemType t =
        b.type == 2 ? ElemType::Tri3 : (b.type == 3 ? ElemType::Quad4 : ElemType::Tet4);
    const std::size_t nn = static_cast<std::size_t>(b.info->num_nodes);
    for (std::size_t i = 0; i < b.tags.size(); ++i) {
      Elem e{b.tags[i], t, {0, 0, 0, 0}, r};
      for (std::size_t k = 0; k < nn; ++k) e.nodes[k] = b.nodes[i * nn + k];
      elems.push_back(e);
    }
  }
  std::stable_sort(elems.begin(), elems.end(),
                   [](const Elem& a, const Elem& b) { return a.tag < b.tag; });

  // Every region has elements.
  std::vector<std::size_t> region_count(mesh.region_names.size(), 0);
  for (const Elem& e : elems) ++region_count[static_cast<std::size_t>(e.region)];
  for (std::size_t r = 0; r < region_count.size(); ++r)
    if (region_count[r] == 0)
      fail(fmt::format("region '{}' (physical group {} of dimension {}) has no elements{}",
                       mesh.region_names[r], region_group[r], top,
                       " (or all of them belong to an earlier physical group)"));

  // Vertices: the nodes of the elements, numbered 0..n-1 in increasing node tag order.
  std::vector<std::size_t> used;
  used.reserve(elems.size() * 4);
  for (const Elem& e : elems)
    for (int k = 0; k < nodes_of(e.type); ++k) used.push_back(e.nodes[static_cast<std::size_t>(k)]);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::unordered_map<std::size_t, std::int32_t> vertex_of;
  vertex_of.reserve(used.size());
  for (std::size_t i = 0; i < used.size(); ++i)
    vertex_of.emplace(used[i], static_cast<std::int32_t>(i));

  {
    std::vector<std::size_t> ntags;
    std::vector<double> coord, param;
    gmsh::model::mesh::getNodes(ntags, coord, param, -1, -1, false, false);
    mesh.vertices.assign(used.size(), Vec3{});
    std::vector<char> found(used.size(), 0);
    for (std::size_t i = 0; i < ntags.size(); ++i) {
      auto it = vertex_of.find(ntags[i]);
      if (it == vertex_of.end()) continue;
      const auto v = static_cast<std::size_t>(it->second);
      mesh.vertices[v] = Vec3{coord[3 * i], coord[3 * i + 1], coord[3 * i + 2]};
      found[v] = 1;
    }
    for (std::size_t v = 0; v < used.size(); ++v)
      if (!found[v])
        fail(fmt::format("node {} is used by elements but has no coordinates", used[v]));
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
  for (const auto& [gdim, gtag] : groups) {
    if (gdim == 0) {
      const std::string name = group_name(gdim, gtag);
      if (std::find(mesh.point_names.begin(), mesh.point_names.end(), name) ==
          mesh.point_names.end())
        mesh.point_names.push_back(name);
    }
    if (gdim != top - 1) continue;
    const std::string name = group_name(gdim, gtag);
    std::vector<int> ents;
    gmsh::model::getEntitiesForPhysicalGroup(gdim, gtag, ents);
    std::vector<std::pair<std::size_t, Facet>> facets;
    for (const Block& b : blocks) {
      if (b.entity_dim != gdim || std::find(ents.begin(), ents.end(), b.entity_tag) == ents.end())
        continue;
      if (b.type != facet_type)
        fail(fmt::format(
            "element {}: a '{}' in face set '{}' (physical group {} of dimension {}); {} face sets "
            "take {} only",
            b.tags.front(), b.info->name, name, gtag, gdim, top == 2 ? "2D" : "3D",
            top == 2 ? "2-node lines" : "3-node triangles"));
      const std::size_t nn = static_cast<std::size_t>(b.info->num_nodes);
      for (std::size_t i = 0; i < b.tags.size(); ++i) {
        Facet f;
        for (std::size_t k = 0; k < nn; ++k) {
          const std::size_t node = b.nodes[i * nn + k];
          auto it = vertex_of.find(node);
          if (it == vertex_of.end())
            fail(fmt::format(
                "element {} of face set '{}': node {} is not a vertex of any {}D element (a face "
                "set must lie on the mesh)",
                b.tags[i], name, node, top));
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

// ---------------------------------------------------------------------------------------------
// Reading

Mesh read_gmsh(const std::string& path) {
  // Check the file before Gmsh sees it: Gmsh does not fail on a missing file.
  {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      throw MeshError(fmt::format("cannot open mesh file '{}': is a directory", path));
    std::ifstream f(path, std::ios::binary);
    if (!f)
      throw MeshError(fmt::format("cannot open mesh file '{}': {}", path, std::strerror(errno)));
  }
  const std::string source = fmt::format("mesh file '{}'", path);
  GmshSession session(source);
  try {
    gmsh::open(path);
    session.check_log();
    return detail::extract_gmsh_model(source);
  } catch (...) {
    session.rethrow_as_mesh_error();
  }
}

// ---------------------------------------------------------------------------------------------
// Writing

void write_gmsh(const Mesh& mesh, const std::string& path) {
  const std::string source = fmt::format("mesh file '{}'", path);
  auto fail = [&](const std::string& what) -> void {
    throw MeshError(fmt::format("cannot write {}: {}", source, what));
  };
  // Structural checks only (a geometrically bad mesh may be written, e.g. for tests).
  const std::size_t ne = mesh.num_elements();
  if (mesh.dim != 2 && mesh.dim != 3)
    fail(fmt::format("mesh dimension {} (expected 2 or 3)", mesh.dim));
  if (mesh.elem_vertices.size() != ne || mesh.elem_region.size() != ne)
    fail("inconsistent element arrays");
  for (std::size_t e = 0; e < ne; ++e) {
    for (int k = 0; k < nodes_of(mesh.elem_type[e]); ++k) {
      const std::int32_t v = mesh.elem_vertices[e][static_cast<std::size_t>(k)];
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.vertices.size())
        fail(fmt::format("element #{}: vertex index {} out of range", e, v));
    }
    if (mesh.elem_region[e] < 0 ||
        static_cast<std::size_t>(mesh.elem_region[e]) >= mesh.region_names.size())
      fail(fmt::format("element #{}: region index {} out of range", e, mesh.elem_region[e]));
  }
  for (const FaceSet& fs : mesh.face_sets)
    for (const Facet& f : fs.facets)
      for (int k = 0; k < f.count(); ++k)
        if (f.v[static_cast<std::size_t>(k)] < 0 ||
            static_cast<std::size_t>(f.v[static_cast<std::size_t>(k)]) >= mesh.vertices.size())
          fail(fmt::format("face set '{}': vertex index out of range", fs.name));
  if (mesh.region_names.empty()) fail("no regions");

  // Element tags: the source's when usable (positive, increasing), else 1..n.
  bool keep_tags = mesh.elem_tag.size() == ne;
  for (std::size_t e = 0; keep_tags && e < ne; ++e)
    keep_tags = mesh.elem_tag[e] > 0 && (e == 0 || mesh.elem_tag[e] > mesh.elem_tag[e - 1]);
  auto elem_tag = [&](std::size_t e) {
    return keep_tags ? static_cast<std::size_t>(mesh.elem_tag[e]) : e + 1;
  };
  std::size_t next_tag = ne == 0 ? 1 : elem_tag(ne - 1) + 1;

  GmshSession session(source);
  try {
    gmsh::model::add("cdem_write");
    const int dim = mesh.dim;
    // Entities: one per region (tag r + 1), all nodes on the first one.
    for (std::size_t r = 0; r < mesh.region_names.size(); ++r)
      gmsh::model::addDiscreteEntity(dim, static_cast<int>(r + 1));
    {
      std::vector<std::size_t> tags(mesh.vertices.size());
      std::vector<double> coord(3 * mesh.vertices.size());
      for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        tags[i] = i + 1;
        coord[3 * i] = mesh.vertices[i].x;
        coord[3 * i + 1] = mesh.vertices[i].y;
        coord[3 * i + 2] = mesh.vertices[i].z;
      }
      gmsh::model::mesh::addNodes(dim, 1, tags, coord);
    }
    auto msh_type = [](ElemType t) {
      return t == ElemType::Tri3 ? 2 : (t == ElemType::Quad4 ? 3 : 4);
    };
    for (std::size_t r = 0; r < mesh.region_names.size(); ++r) {
      std::map<int, std::pair<std::vector<std::size_t>, std::vector<std::size_t>>> by_type;
      for (std::size_t e = 0; e < ne; ++e) {
        if (static_cast<std::size_t>(mesh.elem_region[e]) != r) continue;
        auto& [tags, nodes] = by_type[msh_type(mesh.elem_type[e])];
        tags.push_back(elem_tag(e));
        for (int k = 0; k < nodes_of(mesh.elem_type[e]); ++k)
          nodes.push_back(
              static_cast<std::size_t>(mesh.elem_vertices[e][static_cast<std::size_t>(k)]) + 1);
      }
      std::vector<int> t;
      std::vector<std::vector<std::size_t>> tags, nodes;
      for (auto& [type, tn] : by_type) {
        t.push_back(type);
        tags.push_back(std::move(tn.first));
        nodes.push_back(std::move(tn.second));
      }
      const int tag = static_cast<int>(r + 1);
      if (!t.empty()) gmsh::model::mesh::addElements(dim, tag, t, tags, nodes);
      gmsh::model::addPhysicalGroup(dim, {tag}, tag);
      gmsh::model::setPhysicalName(dim, tag, mesh.region_names[r]);
    }
    // Face sets: one entity and physical group each (empty face sets are not written).
    int fs_tag = 0;
    for (const FaceSet& fs : mesh.face_sets) {
      if (fs.facets.empty()) continue;
      ++fs_tag;
      gmsh::model::addDiscreteEntity(dim - 1, fs_tag);
      std::vector<std::size_t> tags, nodes;
      for (const Facet& f : fs.facets) {
        tags.push_back(next_tag++);
        for (int k = 0; k < f.count(); ++k)
          nodes.push_back(static_cast<std::size_t>(f.v[static_cast<std::size_t>(k)]) + 1);
      }
      gmsh::model::mesh::addElements(dim - 1, fs_tag, {dim == 2 ? 1 : 2}, {tags}, {nodes});
      gmsh::model::addPhysicalGroup(dim - 1, {fs_tag}, fs_tag);
      gmsh::model::setPhysicalName(dim - 1, fs_tag, fs.name);
    }
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".msh") {
      gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
      gmsh::option::setNumber("Mesh.Binary", 0);
    }
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    gmsh::write(path);
    session.check_log();
  } catch (...) {
    session.rethrow_as_mesh_error();
  }
}

}  // namespace cdem
