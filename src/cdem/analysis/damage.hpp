// Damage and fracture degree (SPEC 4).
// Damage of a block: the broken fraction of its interface (spring-point) area, 0..1; damage
// mode: 0 undamaged, 1 tensile, 2 shear, the mode of most of its broken area.
// Fracture degree: broken spring-point area / total spring-point area over the rock's
// interfaces (pre-cracked joints and the unbreakable interfaces around solid charges are
// excluded: they are not blast damage), split into tensile and shear parts, and the
// count-based ratio.
#pragma once
#include <cstdint>
#include <vector>

#include "cdem/core/exact_sum.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

struct FractureDegree {
  double area = 0, tensile = 0, shear = 0;  // area fractions
  double count = 0;                         // count fraction
  std::int64_t broken = 0, total = 0;       // spring points counted
};

// True for spring points that count as rock (breakable, not pre-cracked).
bool counts_as_rock(const Model& m, std::size_t spring);

FractureDegree fracture_degree(const Model& m);

// Fracture degree per region (fracture.csv degree_area_<region>, summary.json
// fracture_degree_regions): for region r, the broken / total area of the rock spring points
// (counts_as_rock) with at least one of their two blocks in r (an interface between two regions
// counts in both). Only regions that have such points are listed (ascending region index): a
// damping ring bonded elastically, or a solid charge, has none.
struct RegionFracture {
  std::vector<std::int32_t> regions;
  std::vector<double> degree;  // area fraction, per listed region
};
RegionFracture fracture_degree_by_region(const Model& m);

// Both, in one pass (a history sample). The areas are summed exactly (core/exact_sum.hpp):
// own_iface (per interface, 1 own; null: all) and r: a part of a distributed run lists its own
// interfaces' points and the sums are reduced over the ranks (every rank calls it at once), with
// the bits one process gets.
struct FractureSummary {
  FractureDegree degree;
  RegionFracture by_region;
};
FractureSummary fracture_summary(const Model& m, const std::uint8_t* own_iface = nullptr,
                                 const SumReducer* r = nullptr);

void block_damage(const Model& m, std::vector<double>& damage, std::vector<std::int32_t>& mode);

}  // namespace cdem
