// The element types of the Gmsh MSH format (the numbers of GmshDefines.h): dimension, node count
// and the name Gmsh gives them. The reader needs the node count to parse a binary file and the
// name for its messages; it must not ask Gmsh (no Gmsh in the read path).
#pragma once

namespace cdem {

struct MshElementType {
  int type = 0;                // MSH element type number
  int dim = 0;                 // 0 point, 1 line, 2 surface, 3 volume
  int nodes = 0;               // nodes per element; 0: variable (polygons), not readable here
  const char* name = nullptr;  // Gmsh's name, e.g. "Triangle 3"
};

// The type with this number, or nullptr when Gmsh 4.8 knows no such type.
const MshElementType* msh_element_type(int type);

}  // namespace cdem
