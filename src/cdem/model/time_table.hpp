// A function of time given as a table of points (a boundary's load or velocity history). Plain
// data: the case file fills it in (case.cpp), the boundary kernels evaluate it.
#pragma once
#include <utility>
#include <vector>

namespace cdem {

// A function of time given as a table of (t, value) points, linearly interpolated, constant
// before the first and after the last point.
struct TimeTable {
  std::vector<std::pair<double, double>> points{{0.0, 1.0}};
  double operator()(double t) const;
};

}  // namespace cdem
