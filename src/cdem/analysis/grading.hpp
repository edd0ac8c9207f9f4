// Fragment size grading (SPEC 4): the cumulative volume percentage passing against the
// characteristic size L_bc (eq. 17), and the sizes d10..d90 (d40 and d80 called out).
//
// Convention (docs/theory_fragments.md):
//  - passing(L) = 100 * (volume of the fragments with L_bc <= L) / (total volume);
//  - the curve is the points (size[i], passing_pct[i]) at the distinct fragment sizes, in
//    increasing order (fragments of equal L_bc make one point), joined by straight lines;
//    the last point is exactly 100 %;
//  - d_x is the smallest size at which the curve reaches x %: if the first point already
//    has passing >= x then d_x = size[0]; otherwise, with i the first point such that
//    passing_pct[i] >= x, d_x interpolates linearly between points i-1 and i.
//  - By default the largest fragment (the intact rock mass in a funnel) is excluded.
//  - Zero-volume fragments carry no weight and are left out. With no fragment left the
//    curve is empty and every d_x is NaN.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "cdem/analysis/fragments.hpp"

namespace cdem {

struct Grading {
  std::vector<double> size;         // distinct L_bc values, increasing, m
  std::vector<double> passing_pct;  // cumulative volume % passing at each size (last: 100)
  std::array<double, 9> d{};        // d[j] = d_(10(j+1)): d10, d20, ..., d90, m
  std::int32_t excluded = -1;       // index of the fragment left out (-1: none)
  double total_volume = 0;          // volume of the fragments on the curve, m^3

  double d40() const { return d[3]; }
  double d80() const { return d[7]; }
};

// The grading curve of `fragments` (any order). exclude_largest leaves out the fragment of
// largest volume (the first one on ties), i.e. fragment 0 of find_fragments.
Grading grading_curve(std::span<const Fragment> fragments, bool exclude_largest = true);

// The same, leaving out fragment `excluded` (an index into `fragments`, or -1 for none); use
// it when the main rock mass is known, e.g. the largest fragment touching a fixed boundary.
Grading grading_curve_excluding(std::span<const Fragment> fragments, std::int32_t excluded);

// d_x for any percentage 0 < pct <= 100 on a curve, by the convention above (NaN if empty).
double size_at_passing(const Grading& g, double pct);

}  // namespace cdem
