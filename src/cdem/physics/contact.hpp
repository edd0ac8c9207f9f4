// General contact (SPEC 1.5, docs/theory.md "General contact"): fragments, released faces and the
// model's boundary faces push on each other and never pass through.
//
// Broad phase: the blocks with a candidate face (the model's boundary faces and the faces of
// interfaces with a released spring point; with candidates = "cracked", with a broken one) are
// hashed by their bounding boxes, grown by their half skins sigma_b (ContactSet::half_skin), into
// a uniform cell grid; every node of a candidate face looks up the cells of its box grown by its
// own sigma_n. A (node, block) pair is kept when the node lies in the block's box grown by
// sigma_n + sigma_b and the two belong to different bodies (blocks connected through points that
// are not released), or either lies on a released face; never the node's own block, nor a block
// holding a node it is bonded to (tied, or joined by a broken point: that point is their contact
// until it is released). Linear in the number of candidates (counting sort into the hash table).
// The list is rebuilt when a candidate node has moved more than its sigma_n since the last build
// (checked every step: no face and node can meet unseen) or when spring points were released.
//
// Each step, a pair that held no contact and whose node is outside the block's bounding sphere or
// in front of one of its face planes (both computed once per block) is skipped: only the pairs
// that pass ("near") go through the narrow phase, the resolution and the gathers. A pair found
// apart is not even tested again until its nodes could have moved far enough to touch (the sleep,
// contact.cpp; the block pairs of the edge contacts likewise, contact_edges.cpp).
//
// Narrow phase, node against block (its candidate faces: triangles in 3D, edges in 2D). With
// g_k = (x - p_k) . n_k the node's signed distance to the plane of face k (outward unit normal
// n_k), the node is inside the block when g_k <= 0 for every face (the blocks are convex), and its
// penetration is d = -max g_k over the block's candidate faces: the distance to the nearest face
// it can leave by. d is continuous as the nearest face changes, so the penalty energy
// k d^2 / 2 is too (a per-face test would switch forces on and off at edges and make energy).
// Penalty, compression only, along that face's normal n:
// F_n = k (d - d0) - c v_n (>= 0; c = 2 zeta sqrt(k m) the optional damping; d0 the ignored
// penetration: when a node comes inside a block deeper than twice its normal approach in one
// step, 2 max(0, -v_n) dt, the excess is not pushed back at once, which would be an impulse from
// nothing, and deeper than that plus the block's tolerance none of it is (the node did not just
// arrive); d0 then only shrinks as the node moves out, as explicit codes treat initial
// penetrations),
// Coulomb friction on an incremental tangential spring k_t = k G/E: F_t += -k_t du_t,
// |F_t| <= mu F_n. The node gets F = F_n n + F_t, the face's nodes -w_i F with w the
// barycentric coordinates of the node's projection (clamped to the face). The stiffness k is the
// contact node's share of the stability budget (tied mode: eta omega_max^2 m / (2 c_max), the
// opened points' stiffness; springs mode: the mean k_n A_c of the node's spring points, counted in
// the springs' step), the smaller of the node's and the block nodes', so contact does not lower
// the time step. Dissipation per pair: the work done on it minus the change of its elastic
// energy F_n^2 / 2k + |F_t|^2 / 2k_t (friction, damping).
//
// Determinism: the pairs are sorted by (node, block); forces are computed per pair in parallel
// and gathered in pair order (node side and block side in two serial passes over the pairs that
// passed the quick reject): bitwise the same for any thread count. Buffers grow only at a
// rebuild.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "cdem/model/model.hpp"

namespace cdem {

// Plain settings ([contact] of the case).
struct ContactSettings {
  bool enabled = false;
  double skin = 0;             // m; > 0: one skin for every block; 0: each block's own
                               // (0.25 x its size; the broad phase below)
  double friction = -1;        // mu; < 0: tan(phi_r) of the interface material of the region pair
  double damping_ratio = 0;    // zeta
  double stiffness_factor = 1; // x the budget stiffness (<= 1)
  // candidates = "cracked" (the default since 7 Dec 2026, with passivity below): the faces of
  // interfaces with a broken point are candidates too, not only released ones ("released": a
  // fragment bounded by cracks that still hold can sink into a third one; about a third of the
  // contact cost; docs/verification_contact.md)
  bool cracked_faces = true;
  // 3D: crossing edges of candidate faces push apart too (contact_edges.cpp)
  bool edges = true;
  // far pairs and block pairs are not tested while they cannot have come near (contact.cpp,
  // contact_edges.cpp); false tests every pair every step (the same results, slower: a check)
  bool sleep = true;
  // A penalty contact stays passive (contact.cpp, "passivity"): energy a node's contacts made
  // (their booked dissipation below zero: an explicit step's kick by a spring the node left within
  // the step, a push handed between blocks) is its debt, taken back by a dashpot on its next
  // contact steps (Hannaford and Ryu 2002, time-domain passivity control). false: the penalty
  // contact as before 7 Dec 2026 (docs/verification_contact.md compares them)
  bool passivity = true;
};

// A candidate block's geometry this step: its bounding sphere grown for the quick reject
// (centre, reach^2), the tolerance of "on a face", and per face a point and the outward normal.
struct BlockPlanes {
  Vec3 c;
  double reach2 = 0, tol = 0;
  // a simplex's tolerance reach: how far a point behind every face plane offset by tol can be
  // from the block (tol x the largest vertex distance from the incentre / the inradius); +inf for
  // a quad or an inverted simplex (contact.cpp, the sleep of far pairs)
  double rho = 0;
  int nf = 0;  // faces
  std::array<Vec3, 4> a0, n;
};

// A tetrahedron's geometry this step for the edge contacts (contact_edges.cpp): its nodes and
// their velocities, per face a point and the outward unit normal, centroid, bounding radius, the
// tolerance of "on a face", and the edges on candidate faces (bit e).
struct TetGeom {
  std::array<Vec3, 4> x, v, n, a0;
  std::array<Vec3, 6> em;      // per edge its midpoint and its length (the edge pairs' first
  std::array<double, 6> el;    // test, bounding spheres: computed once per block, not per pair)
  Vec3 c;
  double r = 0, tol = 0;
  double rho = 0;  // simplex_tolerance_reach
  int cand_edges = 0;
};

// The edge contacts' tests (contact_edges.cpp), here for the tests that compare them:
// a tetrahedron's geometry from its nodes' positions and velocities (every edge a candidate);
// the geometry of an edge pair in contact (the weights s, t of the closest points on the
// pushed edge and on the other, the depth d and the normal n along which the pushed edge is
// pushed); edge ea of A against edge eb of B (0: no contact, 1: A's edge pushed along +n, 2:
// B's); and the edge pairs of A's edges ma and B's mb (bit sets) that it may find in contact
// (bit 6 ea + eb; every pair it finds is among them).
void tet_geom_of(const Vec3* x, const Vec3* v, double block_size, TetGeom& g);
struct EdgeHit {
  double s = 0, t = 0, d = 0;
  Vec3 n;
};
int edge_hit_either(const TetGeom& A, int ea, const TetGeom& B, int eb, EdgeHit& h);
std::uint64_t edge_candidates(const TetGeom& A, int ma, const TetGeom& B, int mb);

struct ContactSet {
  ContactSettings cfg;
  bool enabled = false;
  // The reference skin (m): the one asked, or 0.25 x the median block size. It sets the released
  // faces' overlap tolerance (kReleaseDrift x skin, contact.cpp) for every block.
  double skin = 0;
  // Per block, half its skin sigma_b (m): the skin asked / 2, or by default 0.125 x the block's
  // own size (the largest extent of its box at set-up, block_extent). A (node, block) pair is listed when the node lies within sigma_n + sigma_b of the
  // block's box (sigma_n: that of the node's block), and the list is rebuilt once a candidate
  // node has moved more than its own sigma_n: neither side can then have closed the gap unseen.
  // One global skin (until 4 Dec 2026) was a quarter of the median block, 2.5 element sizes in
  // a graded mesh's fine zone, where a node then saw ~100 blocks (contact_broad_phase.cpp).
  std::vector<double> half_skin;
  // The set-up's half skins; by default (no skin asked) a fast block's half skin is raised at
  // each rebuild to the distance it covers in kSkinSteps steps at its speed then, at most
  // kSkinCap x skin (contact_broad_phase.cpp): one small fragment flying at 400 m/s rebuilt the
  // fine SPEC 5.3 cylinder's pairs every 30 steps.
  std::vector<double> half_skin0;
  int dim = 0;
  // per block face slot 4 b + k (k < 4): the interface it belongs to, -1 for a boundary face
  std::vector<std::int32_t> face_iface;
  std::vector<double> kc;        // per node: penalty stiffness (N/m)
  std::vector<double> mu;        // friction coefficient per (region, region), nreg x nreg
  int nreg = 0;
  double shear_ratio = 0.4;      // k_t / k (G/E of the rock)

  // ---- candidates and pairs (rebuilt) ----
  std::vector<std::int32_t> cand_faces;  // face slots
  std::vector<std::int32_t> cand_nodes;  // ascending
  std::vector<Vec3> x_build;             // per candidate node, at the last build
  std::vector<double> cand_lim2;         // per candidate node, sigma_n^2 (the rebuild trigger;
                                         // from half_skin in index_pairs)
  // The other nodes of the blocks with a candidate face (off every candidate face): watched by
  // the trigger too, since the block's box is what the pairs were listed against, and a block
  // that stretches moves them (ascending; their place at the build; sigma_b^2)
  std::vector<std::int32_t> watch_nodes;
  std::vector<Vec3> watch_x;
  std::vector<double> watch_lim2;
  // rebuild at the next step whatever the trigger says: a checkpoint of a list built on one
  // skin for every block, before each block had its own (a larger sigma there would not hold)
  bool rebuild_due = false;
  std::vector<std::int32_t> pair_node, pair_block;
  // the previous build's pairs (kept for their capacity: a rebuild lists the new pairs here and
  // swaps) and, per new pair, its index among them (-1: a new pair), by which the pairs' state is
  // carried over in place (carry_monotone)
  std::vector<std::int32_t> pair_node_prev, pair_block_prev, pair_from;
  std::vector<double> pair_fn;           // N, >= 0
  std::vector<Vec3> pair_ft;             // tangential force on the node (N)
  std::vector<Vec3> pair_force;          // this step's force on the node (N)
  std::vector<std::array<double, 4>> pair_w;  // this step's weights of the block's nodes
  // this step's geometry of each pair: the gap to the nearest candidate face, its normal, and
  // how deep inside the block the node is (-1: outside); a node inside several blocks of one
  // body (exactly on their shared face or edge) is in contact with the one it is deepest in only
  std::vector<double> pair_g, pair_margin, pair_score;
  std::vector<std::int8_t> pair_kf, pair_kf_now;  // the contact face (local; -1 none): kept from
                                                  // step to step while in contact, and this step's
  std::vector<Vec3> pair_n;
  std::vector<double> pair_k;            // penalty stiffness of the pair (N/m)
  std::vector<double> pair_diss;         // J dissipated by the pair
  std::vector<double> pair_gap;          // this step's effective penetration (m, >= 0; 0 apart)
  std::vector<double> pair_g0;           // penetration ignored, d0 above (m): the depth a node
                                         // already had when it came inside beyond what its
                                         // approach explains (an initial overlap, or a node that
                                         // sank in while a broken point held it); only shrinks
  // the distinct blocks of the pairs, each pair's index among them, their geometry this step
  // (the quick reject and the narrow phase); per block its index (-1: no pair)
  std::vector<std::int32_t> cblock, pair_cb, block_slot;
  std::vector<BlockPlanes> cb_geom;
  // this step: the pairs that pass the quick reject (in pair order), per node with near pairs
  // the start of its run in `near` (+ end), per thread the counts; near_scratch (one slot per
  // pair): each thread's awake pairs at the start of its range of pairs, overwritten by its near
  // pairs as they are found, before the copy to `near`
  std::vector<std::int32_t> near, near_group, near_scratch;
  // per near pair (by its place in `near`) its node, and whether it holds a force this step: read
  // in order by the passes after the narrow phase instead of through the pair's index
  std::vector<std::int32_t> near_node;
  std::vector<std::uint8_t> near_forced;
  std::vector<double> near_dd;   // per near pair: the dissipation it booked this step (J)
  // per node: the energy its node-to-face contacts made and have not yet taken back (J, >= 0;
  // ContactSettings::passivity)
  std::vector<double> node_debt;
  std::vector<std::uint8_t> pair_off;  // this step: the node projects far outside its face
  // far pairs sleep (contact.cpp, kSleepRate): per node its path length (since the first build
  // or the checkpoint loaded: a rebuild keeps it, and the wakes of the pairs that stay with it),
  // per block the path length of its fastest node (the sum over the steps of its nodes' largest
  // |v| dt: a bound on how far each of its nodes has moved), per candidate block that bound (2 j,
  // and 2 j + 1, which is +inf while its tolerance reach is over the cap), per pair the bound at
  // which it is tested again
  std::vector<double> pair_wake, node_drift, blk_drift, cb_drift;
  std::vector<float> pair_gwake;   // per pair: the clock of its node's group (below) before which
                                   // it is not tested again (rounded down: a float halves the
                                   // step's streaming pass)
  // Local clocks for that streaming pass (contact.cpp, kSleepGroup): the blocks in groups of
  // kSleepGroup consecutive ones (the mesh is in Hilbert order, so a group is a compact lump of
  // rock); per group this step's largest node speed, and, per group holding pairs' nodes, the
  // groups of those nodes and of their pairs' blocks (CSR, at the rebuild) and a clock, the sum
  // over the steps of the largest |v| dt among them (no path length of a node or a block of its
  // pairs grew by more). Where one clock for all (until 4 Dec 2026) followed the fastest
  // fragment anywhere, a group's clock follows only the motion near it.
  std::vector<double> grp_speed, grp_clock;
  std::vector<std::int32_t> grp_pair_start, grp_nbr_start, grp_nbr;
  // per candidate block, its pairs (CSR): woken when the block's tolerance reach is over the cap
  std::vector<std::int32_t> cb_pair_start, cb_pair;
  std::vector<std::int64_t> near_count;
  // face-side gather: per node its slot in the step's sums (-1 none), the nodes touched, and
  // their sums (formed in pair order, then added)
  std::vector<std::int32_t> face_slot, face_touched;
  std::vector<Vec3> face_sum;
  // work space of the rebuild
  std::vector<std::int32_t> body, bucket_offset, bucket_entry;
  // per bucket entry, 2 x its block's body + 1 if it has a released candidate face (a bucket's
  // entries ordered by it), and the end of its run of equal keys: the node search passes over
  // the entries of its own body that it may not pair with by the key alone
  std::vector<std::uint32_t> bucket_key;
  std::vector<std::int32_t> bucket_run_end;
  std::vector<std::uint8_t> on_released;
  std::vector<std::uint8_t> face_cand;   // per face slot: 1 when a candidate face

  // ---- edge-to-edge contact (3D, contact_edges.cpp) ----
  bool edges = false;
  // the block pairs (a < b, of different bodies, sorted) whose edges are tested (rebuilt), per
  // awake pair (by its place in bp_awake) this step's contact count (prefix sums), per pair the
  // range of its contacts of the last step
  std::vector<std::int32_t> bp_a, bp_b, bp_prev_n;
  std::vector<std::int64_t> bp_count, bp_prev;
  // per block pair the edge pairs (bit 6 edge of a + edge of b) the count pass found touching
  // this step, and above them its other findings (contact_edges.cpp, kHitsNear): the fill pass
  // tests only those pairs again (sized at the rebuild)
  std::vector<std::uint64_t> bp_hits;
  // this step: the awake block pairs in order, the scratch they are listed in per thread, each
  // thread's count (prefix sums; sized at the rebuild); the block pairs whose bp_prev_n was set
  // (cleared at the next step)
  std::vector<std::int32_t> bp_awake, bp_scratch, bp_prev_set;
  std::vector<std::int64_t> bp_awake_count;
  // the distinct blocks of the block pairs (ascending; rebuilt), each pair's two indices among
  // them, and per block this step's geometry, its bounding sphere among it (computed once per
  // step for the blocks of the awake pairs, not once per pair)
  std::vector<std::int32_t> eb_block, bp_ia, bp_ib;
  std::vector<std::uint8_t> eb_need;  // this step: 1 its geometry is needed, 2 it has it
  std::vector<TetGeom> eb_geom;
  // far block pairs sleep (contact_edges.cpp): per block of the pairs its path-length bound
  // (blk_drift; 2 i, and 2 i + 1, which is +inf when its tolerance reach is over the cap), per
  // block pair the bound at which it is tested again
  std::vector<double> eb_drift, bp_wake;
  // the edge contacts holding something, sorted by (a, b, key = 6 edge of a + edge of b): the
  // ignored depth, the penetration beyond it, the stiffness, the dissipation so far, the force
  // on a's edge, and the weights of the closest points on a's edge (s) and on b's (t)
  std::vector<std::int32_t> ec_a, ec_b, ec_key;
  std::vector<double> ec_d0, ec_gap, ec_k, ec_diss, ec_s, ec_t;
  std::vector<Vec3> ec_force, ec_ft;  // (ec_ft: the tangential part, friction's spring)
  std::vector<std::int32_t> ecn_a, ecn_b, ecn_key;  // this step's list, swapped in at its end
  std::vector<double> ecn_d0, ecn_gap, ecn_k, ecn_diss, ecn_s, ecn_t;
  std::vector<Vec3> ecn_force, ecn_ft;
  std::vector<std::uint8_t> ec_matched;
  double ec_diss_closed = 0;
  std::int64_t ec_active = 0, ec_active_max = 0;

  // ---- state and statistics ----
  std::int64_t released_seen = -1;       // Model::released_points at the last build
  // Since points were released after the last build (contact_release.cpp): the bound sum on the
  // relative motion of the near groups' nodes (2 v_near dt) and of any node (2 max|v| dt) (m)
  double release_drift = 0, release_drift_far = 0;
  // The release trigger's neighbourhood (contact_release.cpp): per block the released points on
  // its interfaces at the last look, and 1 when it lay within kReleaseFar x skin of a block
  // released since the build; per group of kSleepGroup blocks its box this step (the speed pass,
  // contact.cpp); per group the box of its blocks released at this look, and the groups that
  // have one
  std::vector<std::uint8_t> blk_released, blk_near;
  std::vector<std::uint8_t> ifc_free;  // per interface: 1 when all its points are released
  std::vector<Vec3> grp_lo, grp_hi, rel_lo, rel_hi;
  std::vector<std::int32_t> rel_groups;
  std::vector<std::int32_t> join_queue, join_hash;  // scratch of the split test
  std::int64_t released_looked = -1;     // Model::released_points at the last look
  double diss_closed = 0;                // dissipation of pairs dropped at rebuilds (J)
  std::int64_t rebuilds = 0, active = 0, active_max = 0;
  // geometric tests done so far: node-block pairs (sphere and planes), block pairs (edges); the
  // sleep's saving is these against the pairs' count times the steps
  std::int64_t pair_tests = 0, block_pair_tests = 0;
  double max_pen_ratio = 0;              // max over the run of penetration / face block size
  // Where max_pen_ratio was reached (summary.json): a node pressed into a block (node >= 0), or
  // an edge crossing of blocks `block` and `other` (node -1; x the point on block's edge); x the
  // place then; time set by the caller (Simulation) in the step it is found (fresh). block -1:
  // none yet, or a checkpoint written before this was kept.
  struct PenetrationRecord {
    double time = -1;
    std::int32_t node = -1, block = -1, other = -1;
    Vec3 x{};
    bool fresh = false;
  } max_pen_at;
  // the pair buffers' size: the most pairs any build has listed (each of the two lists, this
  // build's and the previous one's, is grown to it when it is short; a checkpoint keeps it, so
  // a restarted run reports what an uninterrupted one does)
  std::size_t pairs_high = 0;
  std::size_t pair_capacity() const { return pairs_high; }
};

// The tolerance reach of a simplex block (Tet4, Tri3) with nodes x, face planes (a0, outward unit
// n) and tolerance tol: how far a point behind every face plane offset by tol can be from the
// block; +inf for a quad (its offset faces need not keep to a scaled copy), an inverted or a flat
// block. Pairs far from a block sleep only while every block they may meet stays within
// kContactRhoCap tol (3 for a regular tetrahedron, 4-10 for most of a Gmsh mesh's; none of the
// late SPEC 5.3 cylinder's over 20): contact.cpp, contact_edges.cpp.
double simplex_tolerance_reach(ElemType t, const Vec3* x, const std::array<Vec3, 4>& a0,
                               const std::array<Vec3, 4>& n, double tol);
constexpr double kContactRhoCap = 20.0;
// The blocks per group of the sleep's local clocks (ContactSet::grp_clock): 16 tetrahedra, 64
// nodes, a lump of about 2.5 block sizes across in the Hilbert-ordered mesh.
constexpr std::int64_t kSleepGroup = 16;
// The fast blocks' half skins (ContactSet::half_skin0): the steps a block at its speed at the
// rebuild may fly before it passes its half skin, and the largest half skin, x the reference
// skin.
constexpr double kSkinSteps = 100.0;
constexpr double kSkinCap = 2.0;

// The largest extent of block b's bounding box (m), in its present place: the default skin's
// measure of a block's size.
double block_extent(const Model& m, std::size_t b);

// Set-up from the model (its interface materials give the friction, the stiffness budget as in
// ties.hpp / springs.hpp). omega2_max: the blocks' omega_max^2 (tied mode), 0 in springs mode.
ContactSet setup_contact(const Model& m, const ContactSettings& cfg, double eta, double omega2_max);

// One step's contact forces added to m.f (call after the block forces). Rebuilds the pairs when
// due. dt: the step (for the tangential increment and the damping).
void contact_forces(Model& m, ContactSet& cs, double dt);

// The broad phase (contact_broad_phase.cpp): the candidate faces and the (node, block) pairs
// anew, the state of the pairs that persist carried over; then index_pairs. dt: the step (the
// fast blocks' half skins).
void rebuild_contact_pairs(Model& m, ContactSet& cs, double dt);

// The release trigger (contact_release.cpp). reset_release_trigger: at each build, every
// released point seen, no block near. release_near_speed: looks at the blocks released since the
// last look (when Model::released_points changed), marks the blocks whose boxes lie within
// `reach` of theirs (needs grp_lo, grp_hi: this step's), and returns the largest speed of the
// nodes of the blocks marked so far.
// sync_release_counts: the per-block released counts and the per-interface free flags of the
// present state (also after a checkpoint is loaded: they are not stored).
void reset_release_trigger(const Model& m, ContactSet& cs);
void sync_release_counts(const Model& m, ContactSet& cs);
double release_near_speed(const Model& m, ContactSet& cs, double reach);

// Rebuilds what is derived from the pairs (the distinct blocks, the step's work lists, their
// capacities): at every rebuild, and after the pairs were loaded from a checkpoint.
void index_pairs(const Model& m, ContactSet& cs);

// The sleep started anew: every pair and block pair tested at the next step, the path lengths
// from 0 (at the first build and after a checkpoint is loaded: the wakes are not stored).
void reset_contact_sleep(const Model& m, ContactSet& cs);

// v[p] = v[from[p]] for from[p] >= 0, else fresh, for p < from.size(), in place: valid when the
// indices from[p] >= 0 increase strictly with p (a merge of two sorted lists). Moves to the left
// are done first, in increasing p, then moves to the right in decreasing p: neither reads a slot
// the other has written (contact_broad_phase.cpp).
template <class T>
void carry_monotone(std::vector<T>& v, const std::vector<std::int32_t>& from, const T& fresh) {
  const std::size_t n = from.size();
  if (v.size() < n) v.resize(n);
  for (std::size_t p = 0; p < n; ++p)
    if (from[p] >= 0 && static_cast<std::size_t>(from[p]) > p) v[p] = v[static_cast<std::size_t>(from[p])];
  for (std::size_t p = n; p-- > 0;)
    if (from[p] >= 0 && static_cast<std::size_t>(from[p]) < p) v[p] = v[static_cast<std::size_t>(from[p])];
  for (std::size_t p = 0; p < n; ++p)
    if (from[p] < 0) v[p] = fresh;
  v.resize(n);
}

// Edge-to-edge contact (3D): the block pairs to test, from the pairs (at each rebuild and after
// loading), and one step's forces added to m.f (its contacts counted into active, its largest
// penetration / block size into pen_ratio).
void index_edge_pairs(const Model& m, ContactSet& cs);
void edge_contact_forces(Model& m, ContactSet& cs, double dt, std::int64_t& active, double& pen_ratio);
// The edge contact that set this step's largest penetration ratio `ratio` (a new largest of the
// run; the node pairs' comes out of their pass) into max_pen_at: found by the same quotient in
// list order (the first of equals), serially over the few edge contacts.
void locate_edge_penetration(const Model& m, ContactSet& cs, double ratio);

// Bytes held by the contact set (capacity x element size of every array).
std::size_t contact_bytes(const ContactSet& cs);

// Elastic energy stored in the contacts (J) and their dissipation so far (J).
double contact_energy(const ContactSet& cs);
double contact_dissipated(const ContactSet& cs);

}  // namespace cdem
