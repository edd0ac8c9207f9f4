#include "cdem/analysis/damage.hpp"

namespace cdem {

bool counts_as_rock(const Model& m, std::size_t s) {
  const auto& im = m.iface_materials[m.iface_material[s / m.springs_per_iface]];
  return im.law != InterfaceLaw::Elastic && !im.precracked;
}

FractureDegree fracture_degree(const Model& m) {
  FractureDegree fd;
  double total = 0, bt = 0, bs = 0;
  for (std::size_t s = 0; s < m.n_springs(); ++s) {
    if (!counts_as_rock(m, s)) continue;
    total += m.sp_area[s];
    ++fd.total;
    if (m.sp_state[s] != kIntact) {
      ++fd.broken;
      (m.sp_mode[s] == kModeShear ? bs : bt) += m.sp_area[s];
    }
  }
  if (total > 0) {
    fd.tensile = bt / total;
    fd.shear = bs / total;
    fd.area = (bt + bs) / total;
    fd.count = static_cast<double>(fd.broken) / static_cast<double>(fd.total);
  }
  return fd;
}

RegionFracture fracture_degree_by_region(const Model& m) {
  const std::size_t nr = m.region_names.size();
  std::vector<double> total(nr, 0.0), broken(nr, 0.0);
  for (std::size_t s = 0; s < m.n_springs(); ++s) {
    if (!counts_as_rock(m, s)) continue;
    const std::size_t i = s / m.springs_per_iface;
    const auto ra = m.block_region[m.iface_block_a[i]], rb = m.block_region[m.iface_block_b[i]];
    const double a = m.sp_area[s], br = m.sp_state[s] != kIntact ? a : 0.0;
    total[ra] += a;
    broken[ra] += br;
    if (rb != ra) {
      total[rb] += a;
      broken[rb] += br;
    }
  }
  RegionFracture rf;
  for (std::size_t r = 0; r < nr; ++r)
    if (total[r] > 0) {
      rf.regions.push_back(static_cast<std::int32_t>(r));
      rf.degree.push_back(broken[r] / total[r]);
    }
  return rf;
}

void block_damage(const Model& m, std::vector<double>& damage, std::vector<std::int32_t>& mode) {
  const std::size_t nb = m.n_blocks();
  std::vector<double> total(nb, 0.0), bt(nb, 0.0), bs(nb, 0.0);
  for (std::size_t s = 0; s < m.n_springs(); ++s) {
    if (!counts_as_rock(m, s)) continue;
    const std::size_t i = s / m.springs_per_iface;
    for (const auto b : {m.iface_block_a[i], m.iface_block_b[i]}) {
      total[b] += m.sp_area[s];
      if (m.sp_state[s] != kIntact) (m.sp_mode[s] == kModeShear ? bs : bt)[b] += m.sp_area[s];
    }
  }
  damage.assign(nb, 0.0);
  mode.assign(nb, 0);
  for (std::size_t b = 0; b < nb; ++b) {
    if (total[b] > 0) damage[b] = (bt[b] + bs[b]) / total[b];
    if (bt[b] + bs[b] > 0) mode[b] = bs[b] > bt[b] ? 2 : 1;
  }
}

}  // namespace cdem
