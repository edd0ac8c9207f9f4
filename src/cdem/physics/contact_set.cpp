// The contact set (physics/contact.hpp): its set-up from the model, the tolerance reach of a
// simplex block (the sleep's and the edge contacts' bound), and the set's accounts (energy,
// dissipation, bytes). Split from contact.cpp, which keeps the per-step narrow phase;
// contact_broad_phase.cpp holds the pairs' search, contact_edges.cpp the edge-to-edge contacts.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cdem/mesh/element_geometry.hpp"
#include "cdem/physics/contact.hpp"

namespace cdem {
namespace {

// The interface material of a region pair, as the topology builder assigns it: the one listing
// the pair, else the default one.
const InterfaceMaterial* iface_material_of(const Model& m, const std::string& ra,
                                           const std::string& rb) {
  const InterfaceMaterial* dflt = nullptr;
  for (const auto& im : m.iface_materials) {
    for (const auto& [a, b] : im.pairs)
      if ((a == ra && b == rb) || (a == rb && b == ra)) return &im;
    if (im.is_default && !dflt) dflt = &im;
  }
  if (!dflt && !m.iface_materials.empty()) dflt = &m.iface_materials.front();
  return dflt;
}

}  // namespace

double block_extent(const Model& m, std::size_t b) {
  Vec3 lo, hi;
  m.block_box(b, lo, hi);
  double e = 0;
  for (int d = 0; d < m.dim; ++d) e = std::max(e, hi[d] - lo[d]);
  return e;
}

ContactSet setup_contact(const Model& m, const ContactSettings& cfg, double eta, double omega2_max) {
  ContactSet cs;
  cs.cfg = cfg;
  cs.enabled = cfg.enabled;
  cs.dim = m.dim;
  if (!cs.enabled) return cs;
  const std::size_t nb = m.n_blocks(), nn = m.n_nodes();
  cs.face_slot.assign(nn, -1);
  cs.node_debt.assign(nn, 0.0);
  const int np = m.springs_per_iface;
  // Block faces -> interfaces.
  cs.face_iface.assign(4 * nb, -1);
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    for (int side = 0; side < 2; ++side) {
      const std::int32_t b = side ? m.iface_block_b[i] : m.iface_block_a[i];
      const std::int32_t* nodes = (side ? m.sp_b.data() : m.sp_a.data()) + i * np;
      const LocalFaces lf = local_faces(m.block_type[b]);
      for (int k = 0; k < lf.count; ++k) {
        int hits = 0;
        for (int a = 0; a < np; ++a)
          for (int c = 0; c < lf.nodes_per_face; ++c)
            hits += m.block_first_node[b] + lf.f[k][c] == nodes[a];
        if (hits == np) cs.face_iface[4 * b + k] = static_cast<std::int32_t>(i);
      }
    }
  }
  // Per-node stiffness. Tied mode: the node's share of the stability budget, as the opened
  // points' (ties.hpp), over the most spring points a node can have (3 in 3D, 2 in 2D).
  // Springs mode: the largest k_n A_c of the node's spring points.
  cs.kc.assign(nn, 0.0);
  const double cmax = m.dim == 3 ? 3.0 : 2.0;
  if (omega2_max > 0) {
    for (std::size_t n = 0; n < nn; ++n) cs.kc[n] = eta * omega2_max * m.mass[n] / (2.0 * cmax);
  } else {
    // the mean k_n A_c of the node's spring points (its share of the springs' step:
    // stable_time_step counts it)
    std::vector<std::int32_t> count(nn, 0);
    for (std::size_t s = 0; s < m.n_springs(); ++s)
      for (auto n : {m.sp_a[s], m.sp_b[s]}) cs.kc[n] += m.sp_kn[s], ++count[n];
    for (std::size_t n = 0; n < nn; ++n)
      if (count[n] > 0) cs.kc[n] /= count[n];
    // nodes without spring points: the springs' formula alpha E / h A_c with alpha = 10,
    // A_c ~ L_c^(dim-1) / (dim) (a face of the block shared by its nodes)
    for (std::size_t b = 0; b < nb; ++b) {
      const auto& mat = m.block_materials[m.block_material[b]];
      const double h = m.block_size[b];
      const double k = 10.0 * mat.youngs / h * std::pow(h, m.dim - 1) / m.dim;
      for (auto n = m.block_first_node[b]; n < m.block_first_node[b + 1]; ++n)
        if (cs.kc[n] <= 0) cs.kc[n] = k;
    }
  }
  for (auto& k : cs.kc) k *= cfg.stiffness_factor;
  cs.edges = cfg.edges && m.dim == 3;
  // Friction per region pair.
  cs.nreg = static_cast<int>(m.region_names.size());
  cs.mu.assign(static_cast<std::size_t>(cs.nreg) * cs.nreg, 0.0);
  constexpr double deg = 3.14159265358979323846 / 180.0;
  for (int a = 0; a < cs.nreg; ++a)
    for (int b = 0; b < cs.nreg; ++b) {
      double mu = cfg.friction;
      if (mu < 0) {
        const auto* im = iface_material_of(m, m.region_names[a], m.region_names[b]);
        mu = im ? std::tan(im->residual_friction() * deg) : 0.5;
      }
      cs.mu[static_cast<std::size_t>(a) * cs.nreg + b] = mu;
    }
  // k_t / k = G / E of the first rock material (the springs' ratio).
  for (const auto& mat : m.block_materials)
    if (mat.explosive.empty()) {
      cs.shear_ratio = mat.shear() / mat.youngs;
      break;
    }
  // Skin: the one asked for every block, or each block's own (a quarter of its size), and the
  // reference skin (the one asked, or a quarter of the median block size).
  if (cfg.skin > 0) {
    cs.skin = cfg.skin;
    cs.half_skin.assign(nb, 0.5 * cfg.skin);
  } else {
    std::vector<double> sz(m.block_size.begin(), m.block_size.end());
    if (!sz.empty()) {
      std::nth_element(sz.begin(), sz.begin() + sz.size() / 2, sz.end());
      cs.skin = 0.25 * sz[sz.size() / 2];
    }
    // (the box's extent, not L_c = (6 V)^(1/3): a sliver reaches as far as a well-shaped block
    // of its edges, though its volume is small)
    cs.half_skin.resize(nb);
    for (std::size_t b = 0; b < nb; ++b) cs.half_skin[b] = 0.125 * block_extent(m, b);
  }
  cs.half_skin0 = cs.half_skin;
  return cs;
}

// The tolerance reach of a simplex (contact.hpp): tol max_i |a_i - I| / r_in, with the incentre
// I = sum_k A_k a_k / sum_k A_k (A_k the measure of the face opposite node k) and the inradius
// r_in = d |b| / sum_k A_k (d the dimension; |b| = A_k h_k / d for every k, h_k the node's height
// above face k: the smallest of these, the larger rho, is taken). The scaled simplex has the faces
// offset by tol exactly: its nodes I + (1 + tol / r_in)(a_i - I) lie tol |a_i - I| / r_in from
// a_i, and a convex set's farthest point from the block is one of its corners.
double simplex_tolerance_reach(ElemType t, const Vec3* x, const std::array<Vec3, 4>& a0,
                               const std::array<Vec3, 4>& n, double tol) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (t != ElemType::Tet4 && t != ElemType::Tri3) return kInf;
  const LocalFaces lf = local_faces(t);
  // the node opposite face k: Tet4's face k is opposite node k, Tri3's edge k (k, k + 1) node k + 2
  auto opposite = [t](int k) { return t == ElemType::Tet4 ? k : (k + 2) % 3; };
  double area[4] = {0, 0, 0, 0}, height[4] = {0, 0, 0, 0}, sum = 0;
  for (int k = 0; k < lf.count; ++k) {
    height[k] = -dot(x[opposite(k)] - a0[k], n[k]);
    if (!(height[k] > 0)) return kInf;  // inverted or flat
    const Vec3 p0 = x[lf.f[k][0]], p1 = x[lf.f[k][1]];
    area[k] = lf.nodes_per_face == 3 ? 0.5 * norm(cross(p1 - p0, x[lf.f[k][2]] - p0)) : norm(p1 - p0);
    sum += area[k];
  }
  double r_in = kInf;
  Vec3 inc{};
  for (int k = 0; k < lf.count; ++k) {
    r_in = std::min(r_in, area[k] * height[k] / sum);
    inc += area[k] * x[opposite(k)];
  }
  inc *= 1.0 / sum;
  double far = 0;
  for (int i = 0; i < lf.count; ++i) far = std::max(far, norm(x[i] - inc));
  return r_in > 0 ? tol * far / r_in : kInf;
}

double contact_energy(const ContactSet& cs) {
  double e = 0;
  for (std::size_t p = 0; p < cs.pair_gap.size(); ++p) {
    const double k = cs.pair_k[p], kt = cs.shear_ratio * k;
    e += 0.5 * k * cs.pair_gap[p] * cs.pair_gap[p] +
         (kt > 0 ? 0.5 * dot(cs.pair_ft[p], cs.pair_ft[p]) / kt : 0.0);
  }
  for (std::size_t i = 0; i < cs.ec_gap.size(); ++i)
    e += 0.5 * cs.ec_k[i] * cs.ec_gap[i] * cs.ec_gap[i] +
         0.5 * dot(cs.ec_ft[i], cs.ec_ft[i]) / (cs.shear_ratio * cs.ec_k[i]);
  return e;
}

double contact_dissipated(const ContactSet& cs) {
  double d = cs.diss_closed + cs.ec_diss_closed;
  for (double x : cs.pair_diss) d += x;
  for (double x : cs.ec_diss) d += x;
  return d;
}

std::size_t contact_bytes(const ContactSet& cs) {
  auto b = [](const auto&... v) { return ((v.capacity() * sizeof(v[0])) + ... + std::size_t{0}); };
  return b(cs.face_iface, cs.kc, cs.mu, cs.cand_faces, cs.cand_nodes, cs.x_build, cs.half_skin, cs.half_skin0, cs.cand_lim2, cs.watch_nodes, cs.watch_x, cs.watch_lim2, cs.pair_node,
           cs.pair_block, cs.pair_node_prev, cs.pair_block_prev, cs.pair_from, cs.pair_fn, cs.pair_ft, cs.pair_force, cs.pair_w, cs.pair_g,
           cs.pair_margin, cs.pair_score, cs.pair_kf, cs.pair_kf_now, cs.pair_n, cs.pair_k,
           cs.pair_diss, cs.pair_gap, cs.pair_g0, cs.cblock, cs.pair_cb, cs.block_slot, cs.cb_geom,
           cs.near, cs.near_group, cs.near_scratch, cs.near_node, cs.near_forced, cs.near_dd, cs.node_debt, cs.pair_off, cs.pair_wake, cs.node_drift, cs.blk_drift,
           cs.pair_gwake, cs.cb_pair_start, cs.cb_pair, cs.grp_speed, cs.grp_clock, cs.grp_pair_start,
           cs.grp_nbr_start, cs.grp_nbr,
           cs.cb_drift, cs.near_count, cs.face_slot, cs.face_touched, cs.face_sum, cs.body,
           cs.bucket_offset, cs.bucket_entry, cs.bucket_key, cs.bucket_run_end, cs.on_released, cs.face_cand, cs.blk_released, cs.blk_near, cs.ifc_free,
           cs.grp_lo, cs.grp_hi, cs.rel_lo, cs.rel_hi, cs.rel_groups, cs.join_queue, cs.join_hash) +
         b(cs.bp_a, cs.bp_b, cs.bp_prev_n, cs.bp_count, cs.bp_prev, cs.bp_hits, cs.bp_awake, cs.bp_scratch, cs.bp_prev_set, cs.bp_awake_count, cs.eb_block, cs.bp_ia, cs.bp_ib,
           cs.eb_need, cs.eb_geom, cs.eb_drift, cs.bp_wake, cs.ec_a, cs.ec_b, cs.ec_key, cs.ec_d0, cs.ec_gap,
           cs.ec_k, cs.ec_diss, cs.ec_s, cs.ec_t, cs.ec_force, cs.ec_ft, cs.ecn_a, cs.ecn_b, cs.ecn_key,
           cs.ecn_d0, cs.ecn_gap, cs.ecn_k, cs.ecn_diss, cs.ecn_s, cs.ecn_t, cs.ecn_force, cs.ecn_ft,
           cs.ec_matched);
}

}  // namespace cdem
