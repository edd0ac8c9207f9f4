#include "cdem/model/time_table.hpp"

#include <algorithm>

namespace cdem {

double TimeTable::operator()(double t) const {
  if (points.empty()) return 1.0;
  if (t <= points.front().first) return points.front().second;
  if (t >= points.back().first) return points.back().second;
  auto it = std::upper_bound(points.begin(), points.end(), t,
                             [](double tt, const auto& p) { return tt < p.first; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  return a.second + (b.second - a.second) * (t - a.first) / (b.first - a.first);
}

}  // namespace cdem
