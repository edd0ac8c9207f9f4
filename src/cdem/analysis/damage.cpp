#include "cdem/analysis/damage.hpp"

namespace cdem {

bool counts_as_rock(const Model& m, std::size_t s) {
  const auto& im = m.iface_materials[m.iface_material[s / m.springs_per_iface]];
  return im.law != InterfaceLaw::Elastic && !im.precracked;
}

FractureSummary fracture_summary(const Model& m, const std::uint8_t* own_iface, const SumReducer* r) {
  // the sums: the totals, then per region r its total area (sum kRegions + 2 r) and its broken
  // area (kRegions + 2 r + 1)
  enum : std::size_t { kTotal, kTensile, kShear, kCount, kBroken, kRegions };
  const std::size_t nr = m.region_names.size();
  const auto np = static_cast<std::size_t>(m.springs_per_iface);
  // (an interface's points' areas added first, in point order: a term of the exact sums need only
  // be the same wherever it is formed)
  const std::vector<double> sum = sum_exactly(kRegions + 2 * nr, [&](auto&& put) {
    std::int64_t total = 0, broken = 0;
    for (std::size_t i = 0; i < m.n_ifaces(); ++i) {
      if ((own_iface && !own_iface[i]) || !counts_as_rock(m, i * np)) continue;
      double all = 0, tensile = 0, shear = 0;
      for (std::size_t s = i * np; s < (i + 1) * np; ++s) {
        const double a = m.sp_area[s];
        all += a;
        if (m.sp_state[s] != kIntact) {
          ++broken;
          (m.sp_mode[s] == kModeShear ? shear : tensile) += a;
        }
      }
      total += static_cast<std::int64_t>(np);
      put(kTotal, all);
      put(kTensile, tensile);
      put(kShear, shear);
      const std::size_t ra = m.block_region[m.iface_block_a[i]], rb = m.block_region[m.iface_block_b[i]];
      put(kRegions + 2 * ra, all);
      put(kRegions + 2 * ra + 1, tensile + shear);
      if (rb != ra) {  // (an interface between two regions counts in both)
        put(kRegions + 2 * rb, all);
        put(kRegions + 2 * rb + 1, tensile + shear);
      }
    }
    put(kCount, static_cast<double>(total));  // (integers below 2^53: exact)
    put(kBroken, static_cast<double>(broken));
  }, r);
  FractureSummary out;
  FractureDegree& fd = out.degree;
  fd.total = static_cast<std::int64_t>(sum[kCount]);
  fd.broken = static_cast<std::int64_t>(sum[kBroken]);
  if (sum[kTotal] > 0) {
    fd.tensile = sum[kTensile] / sum[kTotal];
    fd.shear = sum[kShear] / sum[kTotal];
    fd.area = (sum[kTensile] + sum[kShear]) / sum[kTotal];
    fd.count = static_cast<double>(fd.broken) / static_cast<double>(fd.total);
  }
  for (std::size_t reg = 0; reg < nr; ++reg)
    if (sum[kRegions + 2 * reg] > 0) {
      out.by_region.regions.push_back(static_cast<std::int32_t>(reg));
      out.by_region.degree.push_back(sum[kRegions + 2 * reg + 1] / sum[kRegions + 2 * reg]);
    }
  return out;
}

FractureDegree fracture_degree(const Model& m) { return fracture_summary(m).degree; }

RegionFracture fracture_degree_by_region(const Model& m) { return fracture_summary(m).by_region; }

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
