// Registration metrics on analytic cases: summaries, the exact distance transform against brute
// force, Dice and HD95 of shifted boxes, Jacobians of linear fields, and the field convention
// (LPS components, x_moving = x + u) in warping and in carrying points.

#include "evaluation/registration_metrics.hpp"
#include "geometry/distance_transform.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace phantasm;

namespace {

/// An RAS-oriented grid with the given dims and spacing, origin at index 0.
ImageGrid grid_of(const Eigen::Vector3i& dims, const Eigen::Vector3d& spacing) {
  ImageGrid grid;
  grid.dims = dims;
  grid.spacing_mm = spacing;
  grid.world_from_voxel.topLeftCorner<3, 3>() = spacing.asDiagonal();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-10.0, 5.0, 2.0);
  return grid;
}

std::size_t index_of(const ImageGrid& g, int i, int j, int k) {
  return (static_cast<std::size_t>(k) * g.dims.y() + j) * g.dims.x() + i;
}

/// Labels: `label` in the box [lo, hi) of voxel indices, 0 elsewhere.
std::vector<std::int32_t> box(const ImageGrid& g, const Eigen::Vector3i& lo, const Eigen::Vector3i& hi,
                              std::int32_t label) {
  std::vector<std::int32_t> labels(static_cast<std::size_t>(g.voxel_count()), 0);
  for (int k = lo.z(); k < hi.z(); ++k)
    for (int j = lo.y(); j < hi.y(); ++j)
      for (int i = lo.x(); i < hi.x(); ++i)
        labels[index_of(g, i, j, k)] = label;
  return labels;
}

} // namespace

TEST(RegistrationMetrics, SummaryOfKnownValues) {
  const Summary s = summarize({4.0, 1.0, 3.0, 2.0, 5.0});
  EXPECT_EQ(s.count, 5u);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.sd, std::sqrt(2.5));
  EXPECT_DOUBLE_EQ(s.p95, 4.8); // 0.95 * 4 = 3.8: between 4 and 5
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  EXPECT_EQ(summarize({}).count, 0u);
}

TEST(RegistrationMetrics, DistanceTransformIsExactOnAnAnisotropicGrid) {
  const ImageGrid g = grid_of({13, 9, 7}, {0.7, 1.3, 2.1});
  std::mt19937 random(4);
  std::vector<bool> feature(static_cast<std::size_t>(g.voxel_count()), false);
  for (int n = 0; n < 6; ++n)
    feature[random() % feature.size()] = true;
  const std::vector<double> distance = distance_to(feature, g);
  double worst = 0.0;
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 13; ++i) {
        double best = std::numeric_limits<double>::infinity();
        for (int c = 0; c < 7; ++c)
          for (int b = 0; b < 9; ++b)
            for (int a = 0; a < 13; ++a)
              if (feature[index_of(g, a, b, c)])
                best = std::min(best, Eigen::Vector3d((a - i) * 0.7, (b - j) * 1.3, (c - k) * 2.1).norm());
        worst = std::max(worst, std::abs(best - distance[index_of(g, i, j, k)]));
      }
  EXPECT_LT(worst, 1e-12);
  const std::vector<double> none = distance_to(std::vector<bool>(feature.size(), false), g);
  EXPECT_TRUE(std::isinf(none[0]));
}

// Two 10-voxel cubes, one shifted by 2 voxels along i: Dice 8/10, HD95 the shift in mm.
TEST(RegistrationMetrics, DiceAndHd95OfShiftedBoxes) {
  const ImageGrid g = grid_of({30, 20, 20}, {1.5, 1.0, 1.0});
  const auto fixed = box(g, {5, 5, 5}, {15, 15, 15}, 3);
  const auto shifted = box(g, {7, 5, 5}, {17, 15, 15}, 3);
  const LabelOverlap o = label_overlap(fixed, shifted, g, 3);
  EXPECT_EQ(o.fixed_voxels, 1000);
  EXPECT_EQ(o.warped_voxels, 1000);
  EXPECT_DOUBLE_EQ(o.dice, 0.8);
  EXPECT_NEAR(o.hd95_mm, 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(label_overlap(fixed, fixed, g, 3).hd95_mm, 0.0);
  EXPECT_TRUE(std::isinf(label_overlap(fixed, std::vector<std::int32_t>(fixed.size(), 0), g, 3).hd95_mm));
}

// u = A x (LPS) has det(I + A) everywhere; a field that reverses an axis folds every voxel.
TEST(RegistrationMetrics, JacobianOfLinearFields) {
  const ImageGrid g = grid_of({12, 10, 8}, {2.0, 1.0, 1.5});
  Eigen::Matrix3d a;
  a << 0.1, 0.02, 0.0, -0.03, -0.05, 0.01, 0.0, 0.04, 0.2;
  DisplacementField field = zero_field(g);
  DisplacementField folding = zero_field(g);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 12; ++i) {
        const Eigen::Vector3d lps =
            g.world_from_index(Eigen::Vector3d(i, j, k)).cwiseProduct(Eigen::Vector3d(-1, -1, 1));
        field.lps_mm[index_of(g, i, j, k)] = a * lps;
        folding.lps_mm[index_of(g, i, j, k)] = Eigen::Vector3d(0, 0, -2.5 * lps.z());
      }
  const std::vector<bool> all(static_cast<std::size_t>(g.voxel_count()), true);
  const JacobianStatistics s = jacobian_statistics(field, all);
  const double expected = (Eigen::Matrix3d::Identity() + a).determinant();
  EXPECT_NEAR(s.min_determinant, expected, 1e-12);
  EXPECT_NEAR(s.max_determinant, expected, 1e-12);
  EXPECT_NEAR(s.log_jacobian_sd, 0.0, 1e-12);
  EXPECT_EQ(s.folding_voxels, 0);
  const JacobianStatistics f = jacobian_statistics(folding, all);
  EXPECT_EQ(f.folding_voxels, f.voxels);
  EXPECT_DOUBLE_EQ(f.folding_fraction, 1.0);
  EXPECT_NEAR(f.min_determinant, -1.5, 1e-12);
}

// The convention: u in LPS, a fixed point x lands at x + u. u = (-3, 0, 0) LPS is 3 mm towards
// R+ in RAS: a moving box at i >= 10 (1 mm voxels) appears at i >= 7 on the fixed grid.
TEST(RegistrationMetrics, WarpingAndPointsFollowTheItkConvention) {
  const ImageGrid g = grid_of({24, 6, 6}, {1.0, 1.0, 1.0});
  const auto moving = box(g, {10, 0, 0}, {20, 6, 6}, 2);
  DisplacementField field = zero_field(g);
  for (auto& u : field.lps_mm)
    u = Eigen::Vector3d(-3.0, 0.0, 0.0);
  const auto warped = warp_labels(moving, g, field);
  EXPECT_EQ(warped, box(g, {7, 0, 0}, {17, 6, 6}, 2));
  const Eigen::Vector3d p(1.0, 7.0, 4.0);
  EXPECT_TRUE(field.moved(p).isApprox(Eigen::Vector3d(4.0, 7.0, 4.0)));
  // Trilinear between voxel centres: a field growing along j.
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 24; ++i)
        field.lps_mm[index_of(g, i, j, k)] = Eigen::Vector3d(0.0, 0.0, 0.5 * j);
  const Eigen::Vector3d between = g.world_from_index(Eigen::Vector3d(3.0, 2.25, 1.0));
  EXPECT_NEAR(field.at(between).z(), 1.125, 1e-12);
}
