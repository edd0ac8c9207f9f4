// A mesh as the MSH format and the Gmsh model describe it (nodes by tag, element blocks on
// entities, physical groups of entities), and its assembly into a Mesh with the rules of
// read_gmsh (gmsh_io.hpp). Both the project's MSH reader (msh_reader.hpp) and the extraction of a
// generated Gmsh model fill a RawModel, so files and generated meshes follow one set of rules.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/mesh/mesh.hpp"

namespace cdem {

// Elements of one MSH type on one entity, in file order.
struct RawElementBlock {
  int entity_dim = 0;
  int entity_tag = 0;
  int type = 0;                        // MSH element type (msh_element_types.hpp)
  std::vector<std::uint64_t> tags;     // element tags
  std::vector<std::uint64_t> nodes;    // node tags, (nodes per element) x tags.size()
  std::vector<std::uint64_t> offsets;  // byte offset of each element in the file (may be empty)
};

// A physical group: the entities of dimension `dim` it holds.
struct RawPhysicalGroup {
  int dim = 0;
  int tag = 0;
  std::string name;  // empty: unnamed (named by its tag)
  std::vector<int> entities;
};

struct RawModel {
  std::vector<std::uint64_t> node_tags;     // every node of the file, in file order
  std::vector<Vec3> node_coords;            // same order
  std::vector<std::uint64_t> node_offsets;  // byte offset of each node (may be empty)
  std::vector<RawElementBlock> blocks;      // ordered by (entity dim, entity tag, type)
  std::vector<RawPhysicalGroup> groups;     // ordered by (dim, tag)
  // Where a byte offset is, for messages: e.g. "$Nodes, line 12" (empty function: nowhere).
  std::function<std::string(std::uint64_t)> locate;
};

// Build the Mesh with the rules of read_gmsh and check it (check_mesh). `source` names the
// model in messages ("mesh file 'a.msh'"). Throws MeshError naming the element, node, region or
// face set at fault: no 2D/3D elements, unsupported element types (the top dimension's are
// looked at first, so a mesh of hexahedra is reported as such), an element tag used twice, a
// node tag defined twice or not at all, empty regions or face sets.
Mesh assemble_mesh(const RawModel& raw, const std::string& source);

}  // namespace cdem
