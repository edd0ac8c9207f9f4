// Monitor points (SPEC 4): each named point is located in the block that contains it in the
// reference configuration; a sample is that block's stress, von Mises stress, pressure and the
// mean displacement and velocity of its nodes.
#pragma once
#include <string>
#include <vector>

#include "cdem/analysis/monitor_spec.hpp"
#include "cdem/model/model.hpp"

namespace cdem {

// Block index containing each monitor; throws InputError (naming `where`, the case file, and
// the monitor) for a point outside the mesh.
std::vector<std::int32_t> locate_monitors(const Model& m, const std::vector<Monitor>& monitors,
                                          const std::string& where);

// The block containing point p (reference configuration), or -1.
std::int32_t find_block(const Model& m, Vec3 p);

struct MonitorSample {
  Sym6 stress;
  double von_mises, pressure;
  Vec3 displacement, velocity;
};
MonitorSample sample_block(const Model& m, std::int32_t block);

}  // namespace cdem
