// How big a mesh will be before it is made: the element count of a generated geometry (global
// size, refinements, curved walls, the ring) and the memory a model of that many elements needs,
// checked against what this machine has (core/resources.hpp) before Gmsh meshes for minutes or
// the program is killed for want of memory (docs/input_safety.md).
#pragma once
#include <cstddef>
#include <string>

#include "cdem/mesh/gmsh_io.hpp"

namespace cdem {

// Documented cap on the element count of any model (generated or read), whatever the memory:
// 1e8 elements need ~250 GB and years of steps on one machine; 4-node blocks beyond 5e8 would
// also overflow the 32-bit node numbering.
inline constexpr double kMaxElements = 1e8;

// Peak memory of `cdemblast run` per element (bytes), measured on this project's models
// (docs/input_safety.md): meshing, the CDEM split, the solver arrays and the output buffers.
inline constexpr double kBytesPerElement2D = 2.0e3;
inline constexpr double kBytesPerElement3D = 2.5e3;

struct MeshEstimate {
  double elements = 0;      // expected element count (an upper estimate)
  double bytes = 0;         // memory of a run of such a model
  std::string largest;      // the part of the spec that asks for the most elements, for messages
  std::string largest_key;  // its key under [mesh.generate]: "element_size", "refine[0].size"
};

// An upper estimate of the elements generate_mesh makes for `spec`: the body at element_size
// (ring_element_size in the ring), plus each refinement (its ball at its size and the shell over
// which the size grows back) and each curved wall sized from curvature (circle_segments), each
// counted as if alone. Triangles ~2.3 per h^2, tetrahedra ~6 per h^3 (Gmsh's Delaunay meshes
// give 2.3 and 4.5-6).
MeshEstimate estimate_generated_mesh(const GenerateSpec& spec);

// "" when `elements` of dimension `dim` fit, else why not: "about N elements (<culprit>), more
// than the 1e8 cdemblast takes ..." or "... need about M of memory; this machine has ...",
// above kMaxElements or 80 % of the available memory. `culprit` (may be empty) says which sizes
// ask for them.
std::string model_size_problem(double elements, int dim, const std::string& culprit);

// Throws MeshError "<what>: <model_size_problem>" when there is a problem; `what` names the
// source ("mesh generation", "mesh file 'a.msh'").
void check_model_size(double elements, int dim, const std::string& what,
                      const std::string& culprit);

}  // namespace cdem
