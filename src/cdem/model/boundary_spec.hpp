// A boundary condition (SPEC 1.4) as plain data: which face set, what kind, its value and time
// history. The case file's [[boundary]] tables give them (case.cpp); the boundary kernels
// (physics/boundaries.hpp) and the analysis (main rock mass, reactions) read them without
// knowing where they came from.
#pragma once
#include <string>

#include "cdem/core/vec3.hpp"
#include "cdem/model/time_table.hpp"

namespace cdem {

enum class BoundaryType { Fixed, Roller, NonReflecting, Velocity, Pressure };
inline const char* name_of(BoundaryType b) {
  switch (b) {
    case BoundaryType::Fixed: return "fixed";
    case BoundaryType::Roller: return "roller";
    case BoundaryType::NonReflecting: return "non_reflecting";
    case BoundaryType::Velocity: return "velocity";
    case BoundaryType::Pressure: return "pressure";
  }
  return "?";
}

struct BoundaryCondition {
  std::string faces;        // face set name
  BoundaryType type = BoundaryType::Fixed;
  Vec3 direction{};         // velocity: the velocity vector scaled by `value(t)` (m/s)
  double value = 0;         // pressure (Pa, positive pushes into the body) or velocity scale
  TimeTable table;          // multiplies value
};

}  // namespace cdem
