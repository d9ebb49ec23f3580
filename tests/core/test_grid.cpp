#include "core/grid.hpp"

#include <Eigen/LU>
#include <gtest/gtest.h>

using namespace phantasm;

TEST(AxisCode, RasIsTheIdentityAndLpsNegatesTheFirstTwoAxes) {
  EXPECT_TRUE(direction_from_axis_code("RAS")->isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_TRUE(
      direction_from_axis_code("LPS")->isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));
  EXPECT_TRUE(direction_from_axis_code("ras").has_value());
}

TEST(AxisCode, PermutedCodesMapEachIndexAxisToItsWorldAxis) {
  // "ASR": index axis 0 runs anterior, 1 superior, 2 right.
  const Eigen::Matrix3d d = *direction_from_axis_code("ASR");
  EXPECT_EQ(d.col(0), Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(d.col(1), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(d.col(2), Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR(std::abs(d.determinant()), 1.0, 1e-15);
}

TEST(AxisCode, RejectsRepeatedAxesUnknownLettersAndWrongLengths) {
  for (const char* bad : {"RRS", "RLS", "XYZ", "RA", "RASR", ""}) {
    EXPECT_FALSE(direction_from_axis_code(bad).has_value()) << bad;
  }
}

TEST(CenteredGrid, CentreOfTheVoxelGridIsTheRequestedCentre) {
  for (const char* code : {"RAS", "LPS", "LPI", "SAR"}) {
    const ImageGrid grid =
        make_centered_grid({100, 80, 61}, {2, 1, 0.5}, {10, -20, 5}, *direction_from_axis_code(code));
    const Eigen::Vector3d middle = 0.5 * (grid.dims.cast<double>() - Eigen::Vector3d::Ones());
    EXPECT_TRUE(grid.world_from_index(middle).isApprox(Eigen::Vector3d(10, -20, 5), 1e-12)) << code;
  }
}

TEST(CenteredGrid, DimensionsAreTheRoundedRatioOfFieldOfViewToVoxelSize) {
  const ImageGrid grid =
      make_centered_grid({100, 80, 61}, {2, 1, 0.5}, {0, 0, 0}, Eigen::Matrix3d::Identity());
  EXPECT_EQ(grid.dims, Eigen::Vector3i(50, 80, 122));
  EXPECT_EQ(grid.voxel_count(), 50 * 80 * 122);
  // Neighbouring voxel centres are one voxel size apart along each axis.
  const Eigen::Vector3d step = grid.world_from_index({0, 0, 1}) - grid.world_from_index({0, 0, 0});
  EXPECT_TRUE(step.isApprox(Eigen::Vector3d(0, 0, 0.5)));
}

TEST(CenteredGrid, IndexFromWorldInvertsWorldFromIndex) {
  const ImageGrid grid =
      make_centered_grid({64, 64, 64}, {1.5, 1, 2}, {3, 4, 5}, *direction_from_axis_code("PIL"));
  const Eigen::Vector3d ijk(3.25, 17.5, 9.0);
  EXPECT_TRUE(grid.index_from_world(grid.world_from_index(ijk)).isApprox(ijk, 1e-12));
}

TEST(CenteredGrid, VoxelCountDoesNotOverflowForLargeGrids) {
  ImageGrid grid;
  grid.dims = {4096, 4096, 4096};
  EXPECT_EQ(grid.voxel_count(), std::int64_t{4096} * 4096 * 4096);
}

TEST(VoxelIndex, IRunsFastestThenJThenK) {
  const Eigen::Vector3i dims(4, 3, 5);
  std::size_t expected = 0;
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i)
        EXPECT_EQ(voxel_index(dims, i, j, k), expected++);
}

TEST(Grid, LargestPrimeFactors) {
  EXPECT_EQ(largest_prime_factor(1), 1);
  EXPECT_EQ(largest_prime_factor(2), 2);
  EXPECT_EQ(largest_prime_factor(197), 197);
  EXPECT_EQ(largest_prime_factor(203), 29);
  EXPECT_EQ(largest_prime_factor(240), 5);
  EXPECT_EQ(largest_prime_factor(189), 7);
  EXPECT_EQ(largest_prime_factor(1024), 2);
  EXPECT_EQ(largest_prime_factor(2 * 3 * 101), 101);
  EXPECT_EQ(largest_prime_factor(2147483647), 2147483647); // the largest int, a prime
}
