// The settings of the blast-quality analysis as plain data. The case file's [analysis] table
// gives them (case.cpp); blast_quality.hpp and uplift.hpp read them.
#pragma once
#include <string>
#include <vector>

#include "cdem/core/vec3.hpp"

namespace cdem {

// How the blasting funnel is measured (SPEC 4, docs/theory_fragments.md).
struct AnalysisSettings {
  Vec3 up{};                    // free-surface normal, out of the rock; zero: +y (2D) / +z (3D)
  double surface_level = 0;     // along `up`; used when surface_level_set
  bool surface_level_set = false;  // default: the model's highest point along `up`
  double damage_threshold = 1.0;   // a block counts as broken at this damage (or detached)
  std::vector<std::string> main_faces;  // face sets whose blocks anchor the main rock mass
                                        // (default: the face sets with fixed boundaries)
};

}  // namespace cdem
