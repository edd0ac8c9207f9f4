// Fragments: connected groups of blocks joined through unbroken spring points (SPEC 4), with
// their volume, bounding box, longest box side L_max and characteristic size L_bc (eq. 17):
//   3D: L_bc = (V_f^(1/3) + L_max) / 2
//   2D: L_bc = (A_f^(1/2) + L_max) / 2   (plane strain, unit thickness: the 2D analogue of
//                                          eq. 17, with the fragment's area A_f = V_f / 1 m)
// Pure functions over plain arrays, independent of the solver's data structures.
// Definitions and conventions: docs/theory_fragments.md.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

// Per-block geometry, structure of arrays; every span has the same length n_blocks.
struct BlockGeometry {
  std::span<const double> volume;            // m^3 (2D: area x 1 m); finite and >= 0
  std::span<const Vec3> bbox_min, bbox_max;  // axis-aligned box of the block's current nodes
  std::span<const Vec3> centroid;            // current centroid
  std::span<const Vec3> velocity;            // mean velocity of the block's nodes
};

// Two blocks joined by at least one intact spring point (duplicates and a == b are allowed).
struct Bond {
  std::int32_t a, b;
};

struct Fragment {
  double volume;            // V_f: sum of the blocks' volumes, m^3 (2D: area x 1 m)
  Vec3 bbox_min, bbox_max;  // union of the blocks' bounding boxes
  double l_max;             // longest side of the box, m (2D: of its x and y sides only)
  double l_bc;              // characteristic size, eq. 17 (2D analogue above), m
  Vec3 centroid;            // volume-weighted mean of the block centroids
  Vec3 velocity;            // volume-weighted mean of the block velocities (mass-weighted
                            // for a homogeneous rock)
  std::int32_t blocks;      // number of blocks
};

struct FragmentResult {
  std::vector<std::int32_t> fragment_of_block;  // fragment id of every block
  // Fragment ids 0..k-1 ordered by decreasing volume; equal volumes by their smallest block
  // index. Ids therefore depend only on the geometry and the set of bonds, not on the order
  // of the bonds nor on any thread count.
  std::vector<Fragment> fragments;
};

// Groups the blocks into fragments by union-find (union by size, path compression) over the
// bonds, then aggregates each fragment. dim is 2 or 3. Throws std::invalid_argument on
// mismatched span lengths, a bond index out of range, a negative or non-finite volume, or a
// bad dim. O(n_blocks + n_bonds * alpha(n)) plus a sort of the fragments.
FragmentResult find_fragments(const BlockGeometry& g, std::span<const Bond> bonds, int dim);

// Characteristic size of a fragment of volume `volume` and longest box side `l_max`
// (eq. 17, or its 2D analogue when dim == 2).
double characteristic_size(double volume, double l_max, int dim);

// The largest fragment (smallest id) among those holding the given blocks, e.g. the blocks
// on a fixed boundary: that is the main rock mass of SPEC 4. -1 when `blocks` is empty.
std::int32_t largest_fragment_of(const FragmentResult& r, std::span<const std::int32_t> blocks);

}  // namespace cdem
