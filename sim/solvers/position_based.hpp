// The frame solver both position-based members (sim/solvers/xpbd.cpp, gauss_seidel_pbd.cpp)
// share. Internal to sim.
#pragma once

#include "sim/position_based.hpp"
#include "sim/prepared_solver.hpp"

namespace phantasm::sim_detail {

/// A position-based solver of `variant`: each dynamic step starts from the step's prediction
/// (Macklin et al.), not from the last positions.
std::unique_ptr<PreparedSolver> make_position_based_solver(PositionBasedVariant variant);

} // namespace phantasm::sim_detail
