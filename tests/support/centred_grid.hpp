// A cubic 1 mm test grid centred at the world origin.
#pragma once

#include "core/grid.hpp"

namespace phantasm::testing {

/// n^3 voxels of 1 mm, the grid's centre at the origin.
inline ImageGrid centred_cube_grid(int n) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i::Constant(n);
  grid.spacing_mm = Eigen::Vector3d::Ones();
  grid.world_from_voxel.setIdentity();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-(n - 1) / 2.0);
  return grid;
}

} // namespace phantasm::testing
