// The simulation state as flat arrays (structure of arrays), sized once at set-up.
//
// CDEM layout (SPEC 1): every block owns its nodes, stored contiguously
// (nodes of block b are block_first_node[b] .. block_first_node[b+1]-1), so block kernels
// write forces without conflicts. Blocks are sorted into groups of one element type and one
// kind (elastic rock or explosive), so a kernel runs over a contiguous range with no branch on
// the type. Every interface (a face or edge shared by two blocks) owns `springs_per_iface`
// consecutive spring points (2 in 2D, 3 in 3D): spring s belongs to interface
// s / springs_per_iface, and its node_a lies in block A, node_b in block B.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "cdem/core/vec3.hpp"
#include "cdem/mesh/mesh.hpp"
#include "cdem/model/materials.hpp"

namespace cdem {

// A spring-point quantity that is the same for every spring point of an interface (SPEC 1.3:
// the np spring points of an interface share A_c = A / np and k A_c): stored once per interface
// in `v`, read per spring point s as v[s / per] (per = springs_per_iface).
struct IfaceShared {
  std::vector<double> v;  // per interface
  std::int32_t per = 1;   // spring points per interface
  double operator[](std::size_t s) const { return v[s / static_cast<std::size_t>(per)]; }
};

enum class BlockKind : std::uint8_t { Elastic = 0, Explosive = 1 };

struct BlockGroup {
  ElemType type;
  BlockKind kind;
  std::int32_t begin, end;  // block range
};

enum SpringState : std::uint8_t { kIntact = 0, kBroken = 1, kReleased = 2 };
enum BreakMode : std::uint8_t { kModeNone = 0, kModeTension = 1, kModeShear = 2 };

// The interface of an entry of Model::block_iface_list (i + 1 when the block is A, -(i + 1) when B).
inline std::int32_t block_iface_index(std::int32_t code) { return (code > 0 ? code : -code) - 1; }

struct Model {
  int dim = 0;
  int springs_per_iface = 0;

  // ---- nodes (one per block corner) ----
  // Reference positions: per mesh vertex (the nodes split from a vertex share it), read per node
  // as X(n); 24 B per vertex instead of 24 B per node (a tet mesh has ~5.5 tets per vertex).
  std::vector<Vec3> vertex_X;  // reference position of each mesh vertex (m)
  Vec3 X(std::size_t n) const { return vertex_X[static_cast<std::size_t>(node_vertex[n])]; }
  std::vector<Vec3> X_nodes() const {  // the reference position of every node (a copy)
    std::vector<Vec3> out(node_vertex.size());
    for (std::size_t n = 0; n < out.size(); ++n) out[n] = X(n);
    return out;
  }
  std::vector<Vec3> x;         // current position (m)
  std::vector<Vec3> v;         // velocity at the half step (m/s)
  std::vector<Vec3> f;         // force accumulated in the current step (N)
  std::vector<double> mass;    // lumped mass (kg)
  std::vector<double> inv_mass;       // 1 / mass for the set-up (make_charge_cavities keeps it in
                                      // step); no kernel reads it: Simulation releases it
  std::vector<double> damping;        // mass-proportional damping coefficient (1/s); empty: 0
                                      // everywhere (see release_zero_damping, integrate.hpp)
  std::vector<double> local_damping;  // alpha_L; empty: 0 everywhere
  // The block of node n: a binary search over block_first_node (set-up, messages and tests
  // only; no kernel calls it).
  std::int32_t node_block(std::size_t n) const {
    const auto it = std::upper_bound(block_first_node.begin(), block_first_node.end(),
                                     static_cast<std::int32_t>(n));
    return static_cast<std::int32_t>(it - block_first_node.begin()) - 1;
  }
  std::vector<std::int32_t> node_vertex;  // the mesh vertex it was split from
  // The bounding box of block b's nodes in their present place (x).
  void block_box(std::size_t b, Vec3& lo, Vec3& hi) const {
    lo = hi = x[static_cast<std::size_t>(block_first_node[b])];
    for (auto n = block_first_node[b] + 1; n < block_first_node[b + 1]; ++n)
      for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], x[n][d]), hi[d] = std::max(hi[d], x[n][d]);
  }

  // ---- blocks ----
  std::vector<BlockGroup> groups;
  std::vector<ElemType> block_type;
  std::vector<std::int32_t> block_first_node;  // size n_blocks + 1
  std::vector<std::int32_t> block_region;
  std::vector<std::int32_t> block_material;    // index into block_materials
  std::vector<std::int64_t> block_elem_tag;    // element number in the mesh file
  std::vector<double> block_volume0;           // reference volume (2D: area x 1 m)
  std::vector<double> block_size;              // characteristic size L_c (m), see topology.cpp
  std::vector<double> block_altitude0;         // smallest altitude h_e (m), for the time step
  // Reference shape-function gradients, per block at geom_offset[b]:
  //   tri: 4 doubles, the 2x2 inverse of Dm = [X1-X0, X2-X0] (row-major)
  //   quad: 4 Gauss points x (weight*detJ, 4 nodes x dN/dX, dN/dY) = 4 x 9 doubles
  //   tet: 9 doubles, the 3x3 inverse of Dm = [X1-X0, X2-X0, X3-X0] (row-major)
  std::vector<double> geom;
  std::vector<std::int32_t> geom_offset;       // size n_blocks + 1
  std::vector<Sym6> stress;                    // Cauchy stress (Pa), for output and monitors
  std::vector<Sym6> stress0;                   // initial (in-situ) stress in the block frame;
                                               // empty: zero (Simulation releases it then)
  std::vector<double> strain_energy;           // J, current
  std::vector<double> vol_ratio;               // J = V / V0

  // ---- interfaces and spring points ----
  std::vector<std::int32_t> iface_block_a, iface_block_b;
  std::vector<std::int32_t> iface_material;    // index into spring_laws / iface_materials
  std::vector<Vec3> iface_normal;              // unit normal at the last spring_forces call: the
                                               // previous normal of the next (springs.hpp)
  bool iface_normal_set = false;               // false: rebuild it from x - v dt
  std::vector<std::int32_t> sp_a, sp_b;        // nodes
  IfaceShared sp_area;                         // contact area A_c (m^2), per interface
  IfaceShared sp_kn, sp_ks;                    // stiffness x A_c (N/m), per interface
  std::vector<double> sp_fn;                   // normal force (N), tension positive
  std::vector<Vec3> sp_fs;                     // shear force (N), in the tangent plane
  // Fracture-energy state; empty when no interface law needs it (release_unused_spring_state,
  // springs.hpp): the other laws never change it from 0.
  std::vector<double> sp_w;                    // irreversible opening (m), fracture-energy law
  std::vector<double> sp_slip;                 // accumulated plastic slip (m)
  std::vector<double> sp_dil;                  // dilation opening (m)
  std::vector<double> sp_g0;                   // normal offset carrying an in-situ preload (m);
                                               // empty when there is no initial stress
  std::vector<std::uint8_t> sp_state;          // SpringState
  std::vector<std::uint8_t> sp_mode;           // BreakMode
  std::vector<float> sp_break_time;            // s (-1 intact)
  std::vector<double> sp_dissipated;           // J, fracture + friction + plastic work
  // per block: 1 when it takes no part in general contact (a solid charge's explosive block: its
  // products are a gas, products_leave_contact); empty: every block does
  std::vector<std::uint8_t> no_contact;
  std::int64_t released_points = 0;            // spring points released so far (general contact
                                               // rebuilds its candidates when it changes)
  // The force of spring point s on node a (node b gets minus it) is not stored: it is
  // sp_fn[s] * iface_normal[s / springs_per_iface] + sp_fs[s] (spring_force, springs.hpp).
  std::vector<std::int32_t> block_iface_offset;  // CSR block -> interfaces, size n_blocks + 1
  std::vector<std::int32_t> block_iface_list;    // i + 1 when the block is A, -(i + 1) when B;
                                                 // ascending i (block_iface_index decodes it)

  // ---- tied interfaces (simulation.interfaces = "tied"; physics/ties.hpp) ----
  // The nodes split from one mesh vertex that are joined through tied spring points form a
  // cluster and move as one (one velocity, integrate_tied); a tied point carries no spring force
  // and costs no spring update. A point is untied when the blocks' traction on its face breaks
  // it (tie_failure); it then acts as an ordinary spring point (broken: contact and friction;
  // fracture-energy law: cohesive softening) with the stiffness of opened points.
  bool tied = false;
  std::vector<std::uint8_t> sp_tied;          // 1: the point ties its two nodes
  std::vector<std::int32_t> vtx_offset;       // CSR vertex -> nodes (size n_vertices + 1)
  std::vector<std::int32_t> vtx_nodes;        // per vertex its nodes, cluster by cluster, each
                                              // cluster ascending, clusters by their first node
  std::vector<std::uint8_t> vtx_run;          // 1 at the first node of each cluster (vtx_nodes)
  std::vector<std::uint8_t> iface_check;      // 1: the interface has a tied point that can break
  std::vector<std::uint8_t> iface_active;     // 1: the interface has an untied point (its springs
                                              // are updated); listed in active_ifaces
  std::vector<std::int32_t> active_ifaces;    // capacity n_ifaces, reserved at set-up; ascending
                                              // at the start of a step (order_active_ifaces)
  std::vector<std::int32_t> active_merge;     // scratch of that merge (capacity n_ifaces)
  std::size_t active_sorted = 0;              // leading entries of active_ifaces known ascending
  std::vector<std::uint8_t> block_active;     // 1: the block has an active interface (gather)
  std::vector<std::int32_t> vtx_scratch;      // set-up-sized work space of the cluster split,
  std::size_t vtx_scratch_slot = 0;           // in slots of this size, one per thread
  std::vector<double> tie_reject;             // per interface material: the stress norm (Pa)
                                              // below which no tie can break (tie_failure.cpp)
  std::size_t n_vertices() const { return vtx_offset.empty() ? 0 : vtx_offset.size() - 1; }

  // ---- materials ----
  std::vector<BlockMaterial> block_materials;
  std::vector<InterfaceMaterial> iface_materials;
  std::vector<SpringLaw> spring_laws;          // parallel to iface_materials
  std::vector<double> mat_lambda, mat_shear;   // Lame constants per block material (Pa)
  std::vector<double> mat_beta;                // stiffness-proportional damping per material (s)
  double release_distance_factor = 0.5;        // broken pair released beyond this x block size
  // A broken pair is released too once its two faces have turned apart by more than the release
  // angle: the cosine of that angle (-inf: never, release by distance only; springs.cpp)
  double release_cos = -std::numeric_limits<double>::infinity();

  // ---- regions and boundary facets (from the mesh) ----
  std::vector<std::string> region_names;
  struct BoundaryFacet {
    std::array<std::int32_t, 3> nodes{-1, -1, -1};  // block nodes, outward order
    std::int32_t block = -1;
    int count() const { return nodes[2] < 0 ? 2 : 3; }
  };
  struct FacetSet {
    std::string name;
    std::vector<BoundaryFacet> facets;
  };
  std::vector<FacetSet> facet_sets;

  std::size_t n_nodes() const { return x.size(); }
  std::size_t n_blocks() const { return block_type.size(); }
  std::size_t n_ifaces() const { return iface_block_a.size(); }
  std::size_t n_springs() const { return sp_a.size(); }
  const FacetSet* facet_set(const std::string& name) const {
    for (const auto& s : facet_sets)
      if (s.name == name) return &s;
    return nullptr;
  }
};

}  // namespace cdem
