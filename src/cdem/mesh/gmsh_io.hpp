// Mesh front end: read .msh files (MSH 2.2, 4.0, 4.1, ASCII or binary) with the project's own
// reader (msh_reader.hpp; Gmsh never sees a mesh file: it would run a file it cannot read as a
// mesh as a script), generate simple geometries with Gmsh's OpenCASCADE kernel through the
// Gmsh C++ API, and write .msh files with Gmsh.
#pragma once
#include <cstddef>
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "cdem/mesh/mesh.hpp"

namespace cdem {

// Exclusive, exception-safe use of the Gmsh library, which is a process-wide singleton.
// A session locks a process-wide recursive mutex for its lifetime (other threads wait). The
// outermost session calls gmsh::initialize (no configuration files, General.Terminal = 0,
// General.NumThreads = 1, messages collected by the Gmsh logger) and gmsh::finalize when it
// ends, also through an exception, so every outermost session starts from a clean Gmsh (a
// failed gmsh::open leaves Gmsh unusable until it is finalized). A nested session (the same
// thread, inside another session) works in a fresh model of its own, removes it on exit and
// restores the enclosing model; Gmsh options it changes stay changed. Every use of the Gmsh
// API in the project must happen inside a GmshSession (never call gmsh::initialize directly).
// `context` prefixes error messages, e.g. "mesh file 'a.msh'".
class GmshSession {
 public:
  explicit GmshSession(std::string context);
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  const std::string& context() const { return context_; }
  // Throw MeshError("<context>: <first error>") if Gmsh logged an error since the last call;
  // forward Gmsh warnings to the log (spdlog, level warn).
  void check_log();
  // Translate the exception being handled (Gmsh throws std::string or std::exception) into a
  // MeshError naming the context; a MeshError passes through unchanged. Call from catch (...).
  [[noreturn]] void rethrow_as_mesh_error();

 private:
  std::string context_;
  std::string outer_model_;  // nested session: the enclosing model, restored on exit
  bool nested_ = false;
  std::size_t log_seen_ = 0;  // logger messages already looked at
};

// Check a mesh and bring it to the solver's conventions; `source` names it in messages
// ("mesh file 'x.msh'"). Every MeshError names the source, the element (its elem_tag, the
// number in the file) and what is wrong:
// - consistent sizes and indices, element types of the mesh dimension, facets of dim vertices;
// - 2D: every vertex at |z| <= 1e-12 * extent (then set to exactly 0); area from the cross
//   product; |area| < 1e-12 * mean |area| is "degenerate"; clockwise elements are reordered
//   counter-clockwise (silently: Gmsh gives either orientation); quadrilaterals must be
//   strictly convex (all four corner cross products positive after reordering);
// - 3D: tetrahedron volume V = (x1-x0).((x2-x0)x(x3-x0))/6; |V| < 1e-12 * mean |V| is
//   "degenerate", V < 0 is "inverted tetrahedron (negative volume)" (not reordered: a
//   negative tetrahedron usually means a broken mesh, not a convention);
// - every vertex coordinate finite; before the degenerate test, an element whose |area| or
//   |volume| is more than 1e9 times the median element's is reported as such (a misplaced
//   vertex would otherwise inflate the mean and have a sound element called degenerate);
//   beyond 1e6 times it is a warning.
// read_gmsh and generate_mesh run it on every mesh they return.
void check_mesh(Mesh& mesh, const std::string& source);

// Read a mesh file (MSH 2.2, 4.0 or 4.1, ASCII or binary; anything else is refused, nothing is
// interpreted). Physical groups of the top dimension become regions (elements outside any
// physical group go to a region named "default"); physical groups of dimension dim-1 become
// face sets. Unnamed physical groups are named by their tag ("1", "2", ...).
// Throws MeshError naming the file and the section and line or byte, the element or node, or
// the region at fault: missing or unreadable file, not a regular file, larger than
// max_mesh_file_bytes(), not MSH or a version other than 2.2/4.0/4.1, malformed or truncated
// sections, counts larger than the file could hold, non-finite or huge (> 1e7) coordinates,
// node tags defined twice or used but not defined, element tags used twice, unknown element
// types (anything but 3-node triangles, 4-node quads, 4-node tets and their boundary
// lines/triangles/points), degenerate elements (area/volume below 1e-12 of the mean), inverted
// tetrahedra, non-convex quads, empty regions or face sets.
// MSH 2.2 gives every element its own physical group; an element written once per physical
// group (same tag, type and nodes, as Gmsh writes it) belongs to all of them.
// 2D elements given clockwise are reordered counter-clockwise (that is a convention, not an
// inversion); the mesh must lie in the z = 0 plane.
// Details: the mesh dimension is the highest dimension with elements; lower-dimensional
// elements only serve as facets of face sets (2-node lines in 2D, 3-node triangles in 3D),
// the rest (lines in 3D, points, 2D elements outside face sets in 3D) are ignored. Vertices
// are numbered 0..n-1 in increasing node tag order, over the nodes used by the elements;
// elements are ordered by element tag. An element in two physical groups of the top dimension
// belongs to the first group (lowest tag); groups of the same name are merged. Every facet of
// a face set must use only vertices of the elements.
Mesh read_gmsh(const std::string& path);

// Write a mesh (for examples and tests), format chosen by the extension (.msh: MSH msh_version
// 2.2, 4.0 or 4.1, ASCII or binary; Gmsh 4.8 writes 4.0 in ASCII only; other extensions Gmsh
// knows, e.g. .vtk, are passed to Gmsh). One discrete entity and one physical group per region
// (tag = region index + 1) and per face set; element tags are mesh.elem_tag when those are
// positive and increasing, else 1..n (MSH 2.2: Gmsh numbers the elements it writes 1..n).
// read_gmsh gives the mesh back (same vertices, element order, regions, face sets).
// point_names are not written.
void write_gmsh(const Mesh& mesh, const std::string& path, double msh_version = 4.1,
                bool binary = false);

// A hole. 2D: `depth` == 0 is a circle of `radius` at `center`; `depth` > 0 is a slot, the
// blasthole seen in plane strain: a plain rectangle of width 2 * radius from the collar `center`
// along `axis` (in the xy plane) for `depth`. 3D: a cylinder of `radius` along `axis` through
// the whole body when `depth` == 0, else drilled from `center` along `axis` for `depth`.
struct HoleSpec {
  Vec3 center;
  double radius = 0;
  Vec3 axis{0, 0, 1};
  double depth = 0;
  std::string region;  // non-empty: the hole is filled with elements of this region (a charge)
                       // instead of being empty
};

// Local refinement: element size `size` within `radius` of `point` (or, with `to`, of the
// segment from `point` to `to`: a hole's axis), growing linearly to the global size beyond:
// over a further `radius` when `grading` is 0, else by `grading` metres of size per metre of
// distance (size(d) = size + grading (d - radius) up to element_size). Gmsh MathEval distance
// + Threshold fields (refine_fields in gmsh_generate.cpp).
struct RefineSpec {
  Vec3 point;
  double size = 0;
  double radius = 0;
  std::optional<Vec3> to = std::nullopt;  // the segment's other end; none: a ball around `point`
  double grading = 0;      // > 0: size growth per unit distance; 0: to element_size at 2 radius
};

// Where a refinement's size has grown to element_size: 2 radius (grading 0, the linear ramp
// over a further radius), else radius + (element_size - size) / grading.
inline double refine_outer(const RefineSpec& r, double element_size) {
  const double outer = r.grading > 0 ? r.radius + std::max(0.0, element_size - r.size) / r.grading
                                     : 2 * r.radius;
  return std::max(outer, r.radius * (1 + 1e-6));  // Threshold divides by DistMax - DistMin
}

struct GenerateSpec {
  std::string shape;        // "rectangle" (2D), "box" (3D), "cylinder" (3D, axis z)
  Vec3 origin;              // lower corner (rectangle, box) or base centre (cylinder)
  Vec3 size;                // rectangle: x, y; box: x, y, z; cylinder: radius in x, height in z
  double element_size = 0;  // global target size
  bool quads = false;       // 2D: recombine into quadrilaterals (quad-dominant; leftover tris)
  std::vector<HoleSpec> holes;
  std::vector<RefineSpec> refine;
  double ring_width = 0;         // cylinder: an outer ring of this width is its own region "ring"
  double ring_element_size = 0;  // element size in the ring (0: element_size)
  std::string region = "rock";   // name of the main region
  int circle_segments = 16;      // curved walls: at least this many elements per full turn (sizes
                                 // from curvature, Mesh.MeshSizeFromCurvature); 0: sizes from the
                                 // field only
  // How circle_segments and the size field combine on curved walls: "finest" (the smaller size
  // wins everywhere: Gmsh's sizes from curvature), or "refine" (inside a [[refine]] zone its size
  // wins, larger or smaller; elsewhere as "finest"; curvature sizes from the project's own
  // fields, wall_fields in gmsh_generate.cpp).
  std::string wall_sizing = "finest";
};
// Face sets of generated meshes: rectangle "left" "right" "bottom" "top"; box the same plus
// "front" (y min) and "back" (y max), with "bottom"/"top" at z min/max; cylinder "side",
// "bottom", "top"; each hole "hole0", "hole1", ... (its wall). Regions: `region`, each filled
// hole's region, and "ring" for a cylinder with ring_width > 0.
// Details: the outer face sets hold every boundary facet on that side of the body, also the
// faces of a filled hole that reach it (the collar of a slot is part of "top"); a hole's wall
// is the part of its boundary inside the body (the interface with the rock when it is filled).
// Filled holes and the ring are meshed conformally with the rock (OpenCASCADE fragment). Holes
// with the same region name form one region. The size field is the minimum of the global size
// (ring_element_size in the ring) and each refinement; on curved walls also at most the size
// that cuts a full turn into circle_segments; sizes from points and boundaries are off.
// 2D quads: Frontal-Delaunay triangles recombined by blossom matching (quad-dominant; all quads
// on the shapes tried). Throws MeshError for a bad spec (unknown shape, non-positive sizes, a
// hole outside the body, ...) or when Gmsh fails.
Mesh generate_mesh(const GenerateSpec& spec);

namespace detail {
// Build a Mesh from the current Gmsh model (inside a GmshSession), with the rules of read_gmsh
// (assemble_mesh, mesh_assembly.hpp), and check it (check_mesh). `source` names the model in
// messages. Used by generate_mesh after meshing.
Mesh extract_gmsh_model(const std::string& source);
}  // namespace detail

}  // namespace cdem
