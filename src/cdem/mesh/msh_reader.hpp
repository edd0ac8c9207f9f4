// The project's own reader of Gmsh MSH files: versions 2.2, 4.0 and 4.1, ASCII or binary
// (little-endian). Files are read, never interpreted: no Gmsh in the read path (Gmsh runs any
// file it cannot read as a mesh as a script; docs/input_safety.md).
//
// The reader validates as it goes and names the section and the line (ASCII) or byte (binary)
// of the first problem: a file that is not MSH, an unsupported version, a count larger than the
// rest of the file could hold (checked before anything is allocated), malformed or out-of-range
// numbers, node coordinates that are not finite or beyond 1e7 m, unknown element types, element
// blocks whose type does not match their entity's dimension, sections cut short or missing.
// Sections it does not need ($Periodic, $NodeData, ...) are skipped; partitioned meshes
// ($PartitionedEntities) are refused.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

#include "cdem/mesh/mesh.hpp"
#include "cdem/mesh/mesh_assembly.hpp"

namespace cdem {

// Largest accepted |coordinate| of a node (m): beyond any rock model in any length unit a mesh
// could be written in; larger values are a corrupt file.
inline constexpr double kMaxNodeCoordinate = 1e7;

// Parse the bytes of a MSH file into a RawModel. `source` names the file in messages
// ("mesh file 'a.msh'"). Throws MeshError.
RawModel parse_msh(std::string_view bytes, const std::string& source);

// parse_msh, then assemble_mesh (the rules of read_gmsh, and check_mesh).
Mesh read_msh(std::string_view bytes, const std::string& source);

}  // namespace cdem
