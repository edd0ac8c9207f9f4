// The blasting-quality measures of a model state (SPEC 4): fragments (connected blocks through
// intact spring points), the grading curve of the fragments, and the blasting funnel. Explosive
// blocks are not rock: they get volume 0 and no bonds, so they never count as fragments.
#pragma once
#include <utility>
#include <vector>

#include "cdem/analysis/analysis_spec.hpp"
#include "cdem/analysis/fragments.hpp"
#include "cdem/analysis/funnel.hpp"
#include "cdem/analysis/grading.hpp"
#include "cdem/model/boundary_spec.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

FragmentResult model_fragments(const Model& m);

struct BlastQuality {
  FragmentResult fragments;
  Grading grading;
  Funnel funnel;
  std::int32_t main_fragment = -1;
};

// Fragments, grading (the main rock mass excluded) and funnel of the current state, measured as
// `a` says. The main rock mass is anchored on a.main_faces, by default on the face sets of the
// fixed and roller `boundaries`; `holes`: per hole, its collar and unit direction into the rock
// (FunnelInput::holes).
BlastQuality blast_quality(const Model& m, const AnalysisSettings& a,
                           const std::vector<BoundaryCondition>& boundaries,
                           const std::vector<std::pair<Vec3, Vec3>>& holes);

}  // namespace cdem
