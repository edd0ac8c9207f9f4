// Gmsh front end: the Gmsh session guard, the extraction of a Mesh from the in-memory Gmsh model
// (generate_mesh), read_gmsh (the project's own MSH reader, no Gmsh) and write_gmsh (Gmsh).
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
#include "cdem/core/input_file.hpp"
#include "cdem/mesh/mesh_assembly.hpp"
#include "cdem/mesh/msh_reader.hpp"

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
// Extraction of the current Gmsh model (generated meshes): its nodes, element blocks and
// physical groups as a RawModel, assembled with the same rules as a mesh file.

Mesh detail::extract_gmsh_model(const std::string& source) {
  RawModel raw;
  {
    std::vector<std::size_t> ntags;
    std::vector<double> coord, param;
    gmsh::model::mesh::getNodes(ntags, coord, param, -1, -1, false, false);
    raw.node_tags.assign(ntags.begin(), ntags.end());
    raw.node_coords.resize(ntags.size());
    for (std::size_t i = 0; i < ntags.size(); ++i)
      raw.node_coords[i] = Vec3{coord[3 * i], coord[3 * i + 1], coord[3 * i + 2]};
  }
  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities);  // by dimension, then tag
  for (const auto& [edim, etag] : entities) {
    std::vector<int> etypes;
    std::vector<std::vector<std::size_t>> etags, enodes;
    gmsh::model::mesh::getElements(etypes, etags, enodes, edim, etag);
    for (std::size_t i = 0; i < etypes.size(); ++i) {
      if (etags[i].empty()) continue;
      RawElementBlock b;
      b.entity_dim = edim;
      b.entity_tag = etag;
      b.type = etypes[i];
      b.tags.assign(etags[i].begin(), etags[i].end());
      b.nodes.assign(enodes[i].begin(), enodes[i].end());
      raw.blocks.push_back(std::move(b));
    }
  }
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups);  // by dimension, then tag
  for (const auto& [gdim, gtag] : groups) {
    RawPhysicalGroup g;
    g.dim = gdim;
    g.tag = gtag;
    gmsh::model::getPhysicalName(gdim, gtag, g.name);
    gmsh::model::getEntitiesForPhysicalGroup(gdim, gtag, g.entities);
    raw.groups.push_back(std::move(g));
  }
  return assemble_mesh(raw, source);
}

// ---------------------------------------------------------------------------------------------
// Reading: the project's own MSH reader; Gmsh never sees a mesh file (docs/input_safety.md).

Mesh read_gmsh(const std::string& path) {
  const std::string source = fmt::format("mesh file '{}'", path);
  std::string bytes;
  try {
    const FileLimit limit = max_mesh_file_bytes();
    bytes = read_input_file(path, "mesh file", limit.bytes, limit.reason);
  } catch (const MeshError&) {
    throw;
  } catch (const InputError& e) {
    throw MeshError(e.what());
  }
  return read_msh(bytes, source);
}

// ---------------------------------------------------------------------------------------------
// Writing

void write_gmsh(const Mesh& mesh, const std::string& path, double msh_version, bool binary) {
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
      if (msh_version != 2.2 && msh_version != 4.0 && msh_version != 4.1)
        fail(fmt::format("MSH version {} (expected 2.2, 4.0 or 4.1)", msh_version));
      gmsh::option::setNumber("Mesh.MshFileVersion", msh_version);
      gmsh::option::setNumber("Mesh.Binary", binary ? 1 : 0);
    }
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    gmsh::write(path);
    session.check_log();
  } catch (...) {
    session.rethrow_as_mesh_error();
  }
}

}  // namespace cdem
