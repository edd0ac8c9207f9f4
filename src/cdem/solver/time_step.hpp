// Stable time step (SPEC 1.1):
//   dt = safety * min( min over blocks h_e / c_p , min over nodes sqrt(2 m_i / sum k_n A_c) )
// h_e is the block's smallest altitude; the spring limit uses the normal stiffnesses of the
// spring points attached to node i. The limiting part is reported.
#pragma once
#include <string>

#include "cdem/model/model.hpp"

namespace cdem {

struct StableStep {
  double dt_block = 0;       // min h_e / c_p (s), before the safety factor
  double dt_spring = 0;      // min sqrt(2 m / sum k_n A_c) (s)
  std::int64_t block = -1;   // the limiting block
  std::int64_t node = -1;    // the limiting node (spring limit)
  double dt = 0;             // safety * min
  double safety = 0;         // the safety factor applied
  std::string limit;         // "blocks" or "springs"
};

StableStep stable_time_step(const Model& m, double safety);

}  // namespace cdem
