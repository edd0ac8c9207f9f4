#include "cdem/analysis/blast_quality.hpp"

#include <algorithm>
#include <limits>

#include "cdem/analysis/damage.hpp"

namespace cdem {

FragmentResult model_fragments(const Model& m) {
  const std::size_t nb = m.n_blocks();
  std::vector<double> vol(nb);
  std::vector<Vec3> lo(nb), hi(nb), cen(nb), vel(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    vol[b] = m.block_materials[m.block_material[b]].rock_fraction() * m.block_volume0[b] * m.vol_ratio[b];
    if (!(vol[b] >= 0)) vol[b] = 0.0;  // an inverted block carries no volume
    const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
    lo[b] = hi[b] = m.x[n0];
    Vec3 c{}, v{};
    for (auto n = n0; n < n1; ++n) {
      for (int k = 0; k < 3; ++k) {
        lo[b][k] = std::min(lo[b][k], m.x[n][k]);
        hi[b][k] = std::max(hi[b][k], m.x[n][k]);
      }
      c += m.x[n];
      v += m.v[n];
    }
    cen[b] = c / (n1 - n0);
    vel[b] = v / (n1 - n0);
  }
  std::vector<Bond> bonds;
  const int np = m.springs_per_iface;
  for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
    const auto a = m.iface_block_a[i], b = m.iface_block_b[i];
    if (vol[a] == 0 || vol[b] == 0) continue;
    bool intact = false;
    for (int q = 0; q < np; ++q) intact = intact || m.sp_state[i * np + q] == kIntact;
    if (intact) bonds.push_back({a, b});
  }
  const BlockGeometry g{vol, lo, hi, cen, vel};
  return find_fragments(g, bonds, m.dim);
}

BlastQuality blast_quality(const Model& m, const AnalysisSettings& a,
                           const std::vector<BoundaryCondition>& boundaries,
                           const std::vector<std::pair<Vec3, Vec3>>& holes) {
  BlastQuality q;
  q.fragments = model_fragments(m);
  // The main rock mass: the largest fragment touching the anchoring face sets.
  std::vector<std::string> faces = a.main_faces;
  if (faces.empty())
    for (const auto& bc : boundaries)
      if (bc.type == BoundaryType::Fixed || bc.type == BoundaryType::Roller) faces.push_back(bc.faces);
  std::vector<std::int32_t> anchor;
  for (const auto& name : faces)
    if (const auto* fs = m.facet_set(name))
      for (const auto& f : fs->facets) anchor.push_back(f.block);
  q.main_fragment = anchor.empty() ? (q.fragments.fragments.empty() ? -1 : 0)
                                   : largest_fragment_of(q.fragments, anchor);
  q.grading = q.main_fragment >= 0 ? grading_curve_excluding(q.fragments.fragments, q.main_fragment)
                                   : grading_curve(q.fragments.fragments, false);

  // Funnel, measured on the reference positions.
  const std::size_t nb = m.n_blocks();
  std::vector<Vec3> cen0(nb);
  std::vector<double> vol0(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    const auto n0 = m.block_first_node[b], n1 = m.block_first_node[b + 1];
    Vec3 s{};
    for (auto n = n0; n < n1; ++n) s += m.X(n);
    cen0[b] = s / (n1 - n0);
    vol0[b] = m.block_materials[m.block_material[b]].rock_fraction() * m.block_volume0[b];
  }
  std::vector<double> damage;
  std::vector<std::int32_t> mode;
  block_damage(m, damage, mode);
  FunnelInput in;
  in.centroid = cen0;
  in.volume = vol0;
  in.damage = damage;
  in.fragment_of_block = q.fragments.fragment_of_block;
  in.main_fragment = q.main_fragment;
  in.dim = m.dim;
  in.up = norm(a.up) > 0 ? normalized(a.up) : (m.dim == 2 ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  if (a.surface_level_set) {
    in.surface_level = a.surface_level;
  } else {
    double top = -std::numeric_limits<double>::infinity();
    for (const auto& p : m.X_nodes()) top = std::max(top, dot(p, in.up));
    in.surface_level = top;
  }
  in.damage_threshold = a.damage_threshold;
  in.holes = holes;
  if (q.main_fragment >= 0) q.funnel = blasting_funnel(in);
  return q;
}

}  // namespace cdem
