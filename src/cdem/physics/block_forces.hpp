// Co-rotational linear-elastic block kernels (SPEC 1.2, eq. 6): for each block,
// F = sum_i x_i (x) grad_X N_i, polar split F = R U, eps = U - I,
// S = lambda tr(eps) I + 2 G eps (+ initial stress), nodal force f_i = -V0 R S grad_X N_i,
// Cauchy stress (output) sigma = R S R^T. A rigid rotation gives U = I: no stress.
// Each kernel ASSIGNS the block's nodal forces (the first kernel of the step to write f) and
// stores the block's stress, strain energy and volume ratio J. It returns the number of
// inverted blocks (J <= 0) in the range; the first one is written to *first_inverted.
#pragma once
#include <cstdint>

#include "cdem/model/model.hpp"

namespace cdem {

std::int64_t block_forces_tri(Model& m, std::int32_t begin, std::int32_t end,
                              std::int32_t* first_inverted, bool gather_springs = false);
std::int64_t block_forces_quad(Model& m, std::int32_t begin, std::int32_t end,
                               std::int32_t* first_inverted, bool gather_springs = false);
// Vectorised across blocks (chunks of 8, block_forces.cpp); the same results bit for bit as
// block_forces_tet_reference, one block at a time.
std::int64_t block_forces_tet(Model& m, std::int32_t begin, std::int32_t end,
                              std::int32_t* first_inverted, bool gather_springs = false);
std::int64_t block_forces_tet_reference(Model& m, std::int32_t begin, std::int32_t end,
                                        std::int32_t* first_inverted, bool gather_springs = false);

// All elastic groups; explosive groups are zeroed here and loaded by the explosive kernels.
// gather_springs: then each block also adds its nodes' spring forces (gather_spring_forces for
// its nodes, same sums) right after assigning them: spring_forces must have run first.
// [lo, hi): only the blocks of this range (a rank's share of a distributed run, ranks.hpp);
// each block's results are the same bits whatever the range.
std::int64_t block_forces(Model& m, std::int32_t* first_inverted, bool gather_springs = false,
                          std::int32_t lo = 0, std::int32_t hi = INT32_MAX);

}  // namespace cdem
