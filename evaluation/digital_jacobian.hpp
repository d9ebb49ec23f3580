// Folding by a test finite differences cannot fool: the signed volumes of the tetrahedra of every
// voxel cube after the map x -> x + u(x) (the non-diffeomorphic volume, NDV, of Liu et al.,
// "On finite difference Jacobian computation in deformable image registration", IJCV 2024).
#pragma once

#include "evaluation/registration_metrics.hpp"

#include <cstdint>
#include <vector>

namespace phantasm {

/// The non-diffeomorphic volume of a field over the cubes of eight neighbouring voxel centres
/// whose lowest corner lies in `region`. Each cube is cut into five tetrahedra in each of its two
/// ways; a tetrahedron whose mapped volume is negative adds that volume, and the two cuttings are
/// averaged, so a cube turned inside out counts its whole volume and a regular one nothing. A
/// field whose central-difference Jacobian is positive everywhere may still fold between two
/// voxels (an alternating displacement): this test sees it.
struct FoldingVolume {
  std::int64_t cubes = 0;        ///< cubes tested
  std::int64_t folded_cubes = 0; ///< cubes with a negative tetrahedron
  double ndv_voxels = 0.0;       ///< non-diffeomorphic volume, in voxels
  double ndv_percent = 0.0;      ///< 100 ndv_voxels / cubes
};
FoldingVolume non_diffeomorphic_volume(const DisplacementField& field, const std::vector<bool>& region);

} // namespace phantasm
