#include "cdem/analysis/damage.hpp"

namespace cdem {

bool counts_as_rock(const Model& m, std::size_t s) {
  const auto& im = m.iface_materials[m.iface_material[s / m.springs_per_iface]];
  return im.law != InterfaceLaw::Elastic && !im.precracked;
}

FractureDegree fracture_degree(const Model& m, const std::uint8_t* own_iface, const SumReducer* r) {
  enum : std::size_t { kTotal, kTensile, kShear, kCount, kBroken, kSums };
  const auto np = static_cast<std::size_t>(m.springs_per_iface);
  const std::vector<double> sum = sum_exactly(kSums, [&](auto&& put) {
    std::int64_t total = 0, broken = 0;
    for (std::size_t s = 0; s < m.n_springs(); ++s) {
      if (!counts_as_rock(m, s) || (own_iface && !own_iface[s / np])) continue;
      put(kTotal, m.sp_area[s]);
      ++total;
      if (m.sp_state[s] != kIntact) {
        ++broken;
        put(m.sp_mode[s] == kModeShear ? kShear : kTensile, m.sp_area[s]);
      }
    }
    put(kCount, static_cast<double>(total));  // (integers below 2^53: exact)
    put(kBroken, static_cast<double>(broken));
  }, r);
  FractureDegree fd;
  fd.total = static_cast<std::int64_t>(sum[kCount]);
  fd.broken = static_cast<std::int64_t>(sum[kBroken]);
  if (sum[kTotal] > 0) {
    fd.tensile = sum[kTensile] / sum[kTotal];
    fd.shear = sum[kShear] / sum[kTotal];
    fd.area = (sum[kTensile] + sum[kShear]) / sum[kTotal];
    fd.count = static_cast<double>(fd.broken) / static_cast<double>(fd.total);
  }
  return fd;
}

RegionFracture fracture_degree_by_region(const Model& m, const std::uint8_t* own_iface, const SumReducer* r) {
  const std::size_t nr = m.region_names.size();
  const auto np = static_cast<std::size_t>(m.springs_per_iface);
  // per region r: its total area (sum 2 r) and its broken area (2 r + 1)
  const std::vector<double> sum = sum_exactly(2 * nr, [&](auto&& put) {
    for (std::size_t s = 0; s < m.n_springs(); ++s) {
      if (!counts_as_rock(m, s) || (own_iface && !own_iface[s / np])) continue;
      const std::size_t i = s / np;
      const std::size_t ra = m.block_region[m.iface_block_a[i]], rb = m.block_region[m.iface_block_b[i]];
      const double a = m.sp_area[s];
      const bool broken = m.sp_state[s] != kIntact;
      put(2 * ra, a);
      if (broken) put(2 * ra + 1, a);
      if (rb != ra) {  // (an interface between two regions counts in both)
        put(2 * rb, a);
        if (broken) put(2 * rb + 1, a);
      }
    }
  }, r);
  RegionFracture rf;
  for (std::size_t reg = 0; reg < nr; ++reg)
    if (sum[2 * reg] > 0) {
      rf.regions.push_back(static_cast<std::int32_t>(reg));
      rf.degree.push_back(sum[2 * reg + 1] / sum[2 * reg]);
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
