// The atlases' exact distance transform (atlas/voxel_masks.hpp): against the distance to every
// mask voxel, computed here by brute force, on an anisotropic grid of unequal sides; and their
// connected components against a flood fill.

#include "atlas/voxel_masks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

// Connected components (6-connected, numbered in scan order): against a flood fill from each
// unlabelled mask voxel in scan order, written here, on random masks from sparse to nearly full
// (many components, shapes that meet only late in the scan: U-shapes, spirals of random walks)
// and on a grid of unequal sides; the count is the number of components.
TEST(VoxelMasks, ConnectedComponentsAreTheFloodFillsNumberedInScanOrder) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(31, 19, 23);
  grid.world_from_voxel.setIdentity();
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const auto flood_fill = [&](const voxel_masks::Mask& mask, std::int32_t* components) {
    std::vector<std::int32_t> label(count, 0);
    std::int32_t next = 0;
    for (std::size_t seed = 0; seed < count; ++seed) {
      if (!mask[seed] || label[seed]) continue;
      label[seed] = ++next;
      std::vector<std::size_t> stack{seed};
      while (!stack.empty()) {
        const std::size_t n = stack.back();
        stack.pop_back();
        const int i = static_cast<int>(n % nx), j = static_cast<int>(n / nx % ny),
                  k = static_cast<int>(n / nx / ny);
        const int steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& s : steps) {
          const int a = i + s[0], b = j + s[1], c = k + s[2];
          if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
          const std::size_t m = static_cast<std::size_t>(a + nx * (b + ny * c));
          if (mask[m] && !label[m]) {
            label[m] = next;
            stack.push_back(m);
          }
        }
      }
    }
    *components = next;
    return label;
  };
  std::mt19937 random(11);
  for (const double density : {0.05, 0.2, 0.31, 0.5, 0.7, 0.95}) {
    std::bernoulli_distribution on(density);
    voxel_masks::Mask mask(count, 0);
    for (auto& m : mask)
      m = on(random) ? 1 : 0;
    std::int32_t expected_count = 0, found_count = -1;
    const std::vector<std::int32_t> expected = flood_fill(mask, &expected_count);
    const std::vector<std::int32_t> found = voxel_masks::connected_components(mask, grid, &found_count);
    EXPECT_EQ(found_count, expected_count) << "density " << density;
    EXPECT_EQ(found, expected) << "density " << density;
    EXPECT_GT(expected_count, density < 0.9 ? 1 : 0) << "density " << density;
  }
  // Random walks: long tangled components whose arms join late in the scan.
  voxel_masks::Mask walks(count, 0);
  for (int walk = 0; walk < 6; ++walk) {
    int at[3] = {static_cast<int>(random() % nx), static_cast<int>(random() % ny),
                 static_cast<int>(random() % nz)};
    const int size[3] = {nx, ny, nz};
    for (int step = 0; step < 1500; ++step) {
      walks[static_cast<std::size_t>(at[0] + nx * (at[1] + ny * at[2]))] = 1;
      const int axis = static_cast<int>(random() % 3);
      at[axis] = std::clamp(at[axis] + ((random() & 1) ? 1 : -1), 0, size[axis] - 1);
    }
  }
  std::int32_t expected_count = 0, found_count = -1;
  const std::vector<std::int32_t> expected = flood_fill(walks, &expected_count);
  EXPECT_EQ(voxel_masks::connected_components(walks, grid, &found_count), expected);
  EXPECT_EQ(found_count, expected_count);
  EXPECT_GE(expected_count, 1);
}
