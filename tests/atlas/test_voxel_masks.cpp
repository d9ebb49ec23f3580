// The atlases' exact distance transform (atlas/voxel_masks.hpp): against the distance to every
// mask voxel, computed here by brute force, on an anisotropic grid of unequal sides.

#include "atlas/voxel_masks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace phantasm;

TEST(VoxelMasks, DistanceToIsTheDistanceToTheNearestMaskVoxel) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(23, 17, 29);
  grid.spacing_mm = Eigen::Vector3d(1.0, 0.7, 1.3);
  grid.world_from_voxel.setIdentity();
  grid.world_from_voxel.topLeftCorner<3, 3>() = grid.spacing_mm.asDiagonal();
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  voxel_masks::Mask mask(count, 0);
  std::mt19937 random(3);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(count) - 1);
  for (int k = 0; k < 12; ++k)
    mask[static_cast<std::size_t>(pick(random))] = 1;
  const std::vector<float> distance = voxel_masks::distance_to(mask, grid);
  ASSERT_EQ(distance.size(), count);
  const auto at = [&](std::size_t n) -> Eigen::Vector3d {
    const auto i = static_cast<int>(n % static_cast<std::size_t>(grid.dims.x()));
    const auto j = static_cast<int>(n / static_cast<std::size_t>(grid.dims.x()) %
                                    static_cast<std::size_t>(grid.dims.y()));
    const auto k = static_cast<int>(n / static_cast<std::size_t>(grid.dims.x() * grid.dims.y()));
    return Eigen::Vector3d(i, j, k).cwiseProduct(grid.spacing_mm);
  };
  int zeros = 0;
  for (std::size_t n = 0; n < count; ++n) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t m = 0; m < count; ++m)
      if (mask[m]) nearest = std::min(nearest, (at(n) - at(m)).norm());
    ASSERT_NEAR(distance[n], nearest, 1e-5 * (1.0 + nearest)) << "voxel " << n;
    zeros += distance[n] == 0.0F;
  }
  EXPECT_EQ(zeros, 12);
}
