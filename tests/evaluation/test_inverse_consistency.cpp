// Inverse consistency on analytic fields: a map and its inverse bring every point home (the
// backward field read where the forward one lands: read at the starting voxel, a rotation and its
// inverse would not cancel), a map followed by itself does not, and a curved map leaves only
// interpolation error.

#include "evaluation/field_conventions.hpp"
#include "evaluation/inverse_consistency.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>

using namespace phantasm;

namespace {

ImageGrid oblique_grid() {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(24, 20, 18);
  grid.spacing_mm = Eigen::Vector3d(2.0, 1.5, 2.5);
  grid.world_from_voxel.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
      grid.spacing_mm.asDiagonal();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-20.0, -14.0, -22.0);
  return grid;
}

/// The field x -> map(x) - x (RAS mm) on `grid`.
DisplacementField field_of(const ImageGrid& grid,
                           const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& map) {
  std::vector<Eigen::Vector3d> ras(static_cast<std::size_t>(grid.voxel_count()));
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        ras[voxel_index(grid.dims, i, j, k)] = map(x) - x;
      }
  return field_from_ras(grid, ras);
}

/// Voxels at least `margin` voxels from the border (where a map of a few mm stays inside).
std::vector<bool> inner(const ImageGrid& grid, int margin) {
  std::vector<bool> mask(static_cast<std::size_t>(grid.voxel_count()), false);
  for (int k = margin; k < grid.dims.z() - margin; ++k)
    for (int j = margin; j < grid.dims.y() - margin; ++j)
      for (int i = margin; i < grid.dims.x() - margin; ++i)
        mask[voxel_index(grid.dims, i, j, k)] = true;
  return mask;
}

double largest(const std::vector<double>& values) {
  return values.empty() ? -1.0 : *std::max_element(values.begin(), values.end());
}

} // namespace

TEST(InverseConsistency, AnAffineMapAndItsInverseBringEveryPointHome) {
  const ImageGrid grid = oblique_grid();
  const Eigen::Vector3d centre = grid.world_from_index(grid.dims.cast<double>() / 2.0);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, -0.4, 1.0).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(2.0, -1.5, 1.0);
  const DisplacementField forward = field_of(grid, [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(rotation * (x - centre) + centre + shift);
  });
  const DisplacementField backward = field_of(grid, [&](const Eigen::Vector3d& y) {
    return Eigen::Vector3d(rotation.transpose() * (y - shift - centre) + centre);
  });
  const std::vector<bool> mask = inner(grid, 5);
  const std::vector<double> errors = inverse_consistency_errors(forward, backward, mask);
  ASSERT_EQ(errors.size(), static_cast<std::size_t>(std::count(mask.begin(), mask.end(), true)));
  // Affine fields are reproduced exactly by trilinear interpolation: only rounding is left.
  EXPECT_LT(largest(errors), 1e-9);
}

TEST(InverseConsistency, AMapFollowedByItselfIsOffByTwiceItsMotion) {
  const ImageGrid grid = oblique_grid();
  const Eigen::Vector3d shift(2.0, -1.5, 1.0);
  const DisplacementField forward =
      field_of(grid, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(x + shift); });
  const std::vector<double> errors = inverse_consistency_errors(forward, forward, inner(grid, 5));
  ASSERT_FALSE(errors.empty());
  for (double e : errors)
    EXPECT_NEAR(e, 2.0 * shift.norm(), 1e-9);
}

TEST(InverseConsistency, ACurvedMapAndItsInverseLeaveOnlyInterpolationError) {
  // A quadratic bend along x that depends on y, which the map keeps: its exact inverse bends back.
  const ImageGrid grid = oblique_grid();
  const Eigen::Vector3d centre = grid.world_from_index(grid.dims.cast<double>() / 2.0);
  auto bend = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d d = x - centre;
    return Eigen::Vector3d(0.01 * d.y() * d.y(), 0.0, 0.0);
  };
  const DisplacementField forward =
      field_of(grid, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(x + bend(x)); });
  const DisplacementField backward =
      field_of(grid, [&](const Eigen::Vector3d& y) { return Eigen::Vector3d(y - bend(y)); });
  const std::vector<bool> mask = inner(grid, 5);
  const std::vector<double> errors = inverse_consistency_errors(forward, backward, mask);
  ASSERT_FALSE(errors.empty());
  double sum = 0.0;
  for (double e : errors)
    sum += e;
  // Trilinear interpolation of a quadratic: small, not zero.
  EXPECT_LT(sum / static_cast<double>(errors.size()), 0.02);
  EXPECT_LT(largest(errors), 0.05);
}
