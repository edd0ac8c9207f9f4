// Blasting funnel (SPEC 4): the broken zone (blocks detached from the main rock mass or fully
// damaged) measured as its depth below the free surface, its extents l_x, l_y at the surface,
// the axial ratio e = l_y / l_x and the footage (depth of the broken zone along the holes).
//
// Procedure (docs/theory_fragments.md, "Blasting funnel"):
//  - h = typical block size = median over all blocks of volume^(1/dim) (2D: area^(1/2)).
//  - A block is a cube (2D: square) of side s_i = volume_i^(1/dim) centred at its centroid:
//    its extent along any direction is centroid +- s_i / 2.
//  - broken: fragment_of_block != main_fragment, or damage >= damage_threshold.
//  - depth = max over broken blocks of (surface_level - centroid.up + s_i / 2), >= 0. Every
//    broken block counts, whether or not the broken zone connects it to the surface.
//  - l_x, l_y: extents along the horizontal axes x' and y' of the broken blocks of the top
//    layer (centroid at most h below the surface), each block padded by s_i / 2 on both
//    sides. x' = x_axis projected on the surface plane, y' = up x x'. 2D: l_y = 0.
//  - axial_ratio = l_y / l_x (0 when l_x = 0, and always 0 in 2D where it is undefined).
//  - footage of a hole (collar p, unit direction d into the rock): stations s_k = k h / 2,
//    k = 0, 1, ...; a broken block whose centroid lies within 1.5 h of the axis covers the
//    stations in t_i +- s_i / 2, t_i = (centroid - p).d; the footage is the last station
//    before the first uncovered one (0 if the collar station is uncovered).
//    footage = mean over the holes (0 with no hole).
#pragma once
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

struct FunnelInput {
  std::span<const Vec3> centroid;  // per block; pass the initial (undeformed) positions
  std::span<const double> volume;  // m^3 (2D: area x 1 m)
  std::span<const double> damage;  // 0..1 per block
  std::span<const std::int32_t> fragment_of_block;
  std::int32_t main_fragment = 0;  // the main rock mass: the largest fragment touching a
                                   // fixed boundary (see largest_fragment_of)
  Vec3 up{0, 0, 1};                // free-surface normal, out of the rock (2D: {0, 1, 0})
  double surface_level = 0;        // coordinate of the free surface along `up`, m
  double damage_threshold = 1.0;   // broken when damage >= this (fully damaged) or detached
  std::vector<std::pair<Vec3, Vec3>> holes;  // per hole: collar point, direction into rock
  int dim = 3;
  Vec3 x_axis{1, 0, 0};  // direction of l_x (projected on the surface plane; if parallel to
                         // `up`, the y axis is used instead)
};

struct Funnel {
  double depth = 0;         // m below the surface
  double l_x = 0, l_y = 0;  // extents of the broken zone at the surface, m
  double axial_ratio = 0;   // e = l_y / l_x
  double footage = 0;       // mean of footage_per_hole, m
  std::vector<double> footage_per_hole;
  std::int64_t broken_blocks = 0;
  double broken_volume = 0;  // m^3 (2D: area x 1 m)
  double typical_size = 0;   // h, m
};

// Throws std::invalid_argument on mismatched span lengths, dim not 2 or 3, a zero `up` or
// hole direction, or a typical size that is not positive.
Funnel blasting_funnel(const FunnelInput& in);

}  // namespace cdem
