// Inverse consistency of a method that returns both directions of a pair: the forward field
// (on the fixed grid, carrying fixed points into the moving image) followed by the backward one
// (on the moving grid, carrying moving points back into the fixed image) should bring every
// point home.
#pragma once

#include "evaluation/registration_metrics.hpp"

#include <vector>

namespace phantasm {

/// |phi_ba(phi_ab(x)) - x| in mm at every voxel x of `forward`'s grid inside `mask`, where
/// phi_ab(x) = x + u_ab(x) and the backward field is read at phi_ab(x) (trilinear, clamped at its
/// border). Both fields in the convention of registration_metrics.hpp.
/// @param mask forward.grid.voxel_count() flags (the voxels where the truth is exact)
std::vector<double> inverse_consistency_errors(const DisplacementField& forward,
                                               const DisplacementField& backward,
                                               const std::vector<bool>& mask);

} // namespace phantasm
