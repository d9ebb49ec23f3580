// A label volume's implicit shape (anatomy/file_shapes.cpp): its value is the Gaussian-smoothed
// indicator of the labels, less 1/2, trilinear between voxel centres. Checked against the direct
// three-dimensional sum of the kernel over the labels, computed here independently.

#include "anatomy/phantom.hpp"

#include "tests/support/centred_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

using namespace phantasm;

TEST(LabelShape, SmoothedValueAtEveryVoxelCentreIsTheNormalizedGaussianSumOfTheLabels) {
  const int n = 40;
  const ImageGrid grid = phantasm::testing::centred_cube_grid(n);
  // Label 2 on a ball of radius 12 mm with a slab of label 5 through it and a one-voxel spike:
  // interfaces of every orientation, a thin feature, and voxels of a label outside the set.
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  const auto index = [n](int i, int j, int k) { return static_cast<std::size_t>((k * n + j) * n + i); };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        if (x.norm() <= 12.0) labels[index(i, j, k)] = std::abs(x.z() - 2.0) < 1.5 ? 5 : 2;
      }
  for (int i = 25; i < 34; ++i)
    labels[index(i, 20, 20)] = 2;
  const double sigma = 1.3;
  const auto shape = make_label_shape(grid, labels, {2}, sigma, "ball");

  const int half = static_cast<int>(std::ceil(3.0 * sigma));
  std::vector<double> kernel(static_cast<std::size_t>(2 * half + 1));
  double norm = 0.0;
  for (int t = -half; t <= half; ++t)
    norm += kernel[static_cast<std::size_t>(t + half)] =
        static_cast<double>(static_cast<float>(std::exp(-0.5 * t * t / (sigma * sigma))));
  // The shape keeps the labels' voxel box widened by the kernel's reach and a voxel, and
  // renormalizes the kernel at its faces: within a voxel of the labels' box every window lies
  // inside it.
  Eigen::Vector3i low = Eigen::Vector3i::Constant(n), high = Eigen::Vector3i::Constant(-1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        if (labels[index(i, j, k)] == 2) {
          low = low.cwiseMin(Eigen::Vector3i(i, j, k));
          high = high.cwiseMax(Eigen::Vector3i(i, j, k));
        }
  ASSERT_GE(low.minCoeff() - 1 - half, 0);
  ASSERT_LT(high.maxCoeff() + 1 + half, n);
  int checked = 0, between = 0;
  for (int k = low.z() - 1; k <= high.z() + 1; ++k)
    for (int j = low.y() - 1; j <= high.y() + 1; ++j)
      for (int i = low.x() - 1; i <= high.x() + 1; ++i) {
        double sum = 0.0;
        for (int c = -half; c <= half; ++c)
          for (int b = -half; b <= half; ++b)
            for (int a = -half; a <= half; ++a)
              if (labels[index(i + a, j + b, k + c)] == 2)
                sum += kernel[static_cast<std::size_t>(a + half)] *
                       kernel[static_cast<std::size_t>(b + half)] *
                       kernel[static_cast<std::size_t>(c + half)];
        const double expected = sum / (norm * norm * norm) - 0.5;
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        ASSERT_NEAR(shape->value(x), expected, 2e-6) << "voxel " << i << " " << j << " " << k;
        ++checked;
        between += std::abs(expected) < 0.49;
      }
  EXPECT_GT(checked, 15000);
  EXPECT_GT(between, 2000); // the check reaches the smoothed band, not only the flat 0s and 1s
}
