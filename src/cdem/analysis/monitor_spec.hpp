// A monitor point (SPEC 4) as plain data: its name and where it is. The case file's
// [[monitor]] tables give them (case.cpp); monitors.hpp locates and samples them.
#pragma once
#include <string>

#include "cdem/core/vec3.hpp"

namespace cdem {

struct Monitor {
  std::string name;
  Vec3 point;
};

}  // namespace cdem
