// A label volume's implicit shape (anatomy/file_shapes.cpp): its value is the Gaussian-smoothed
// indicator of the labels, less 1/2, trilinear between voxel centres. Checked against the direct
// three-dimensional sum of the kernel over the labels, computed here independently; its slope
// bound against the slopes met along lines, and the fit that uses the bound against the fit
// without it.

#include "anatomy/patch_fit.hpp"
#include "anatomy/phantom.hpp"

#include "tests/support/centred_grid.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
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

namespace {

/// A torus of label 3 (major radius 10 mm, tube 4 mm) on a grid of 1.2 x 0.8 x 1 mm voxels turned
/// by 30 degrees about z and shifted: anisotropic, oblique voxels, and a shape no ray from its
/// centre samples (not star-shaped), so the fit extracts its surface and steps along normals.
std::unique_ptr<ImplicitShape> oblique_torus(double smoothing_mm) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(36, 52, 24);
  grid.spacing_mm = Eigen::Vector3d(1.2, 0.8, 1.0);
  const double angle = 30.0 * 3.14159265358979 / 180.0;
  Eigen::Matrix3d rotation;
  rotation << std::cos(angle), -std::sin(angle), 0, std::sin(angle), std::cos(angle), 0, 0, 0, 1;
  grid.world_from_voxel.setIdentity();
  grid.world_from_voxel.topLeftCorner<3, 3>() = rotation * grid.spacing_mm.asDiagonal();
  const Eigen::Vector3d centre_index = (grid.dims.cast<double>() - Eigen::Vector3d::Ones()) / 2.0;
  grid.world_from_voxel.topRightCorner<3, 1>() =
      Eigen::Vector3d(3.0, -2.0, 1.0) - grid.world_from_voxel.topLeftCorner<3, 3>() * centre_index;
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  std::size_t n = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i, ++n) {
        const Eigen::Vector3d x =
            grid.world_from_index(Eigen::Vector3d(i, j, k)) - Eigen::Vector3d(3.0, -2.0, 1.0);
        const double ring = std::hypot(x.x(), x.y()) - 10.0;
        if (std::hypot(ring, x.z()) <= 4.0) labels[n] = 3;
      }
  return make_label_shape(grid, labels, {3}, smoothing_mm, "torus");
}

/// Forwards everything but the slope bound and the solid box, which it leaves at the defaults
/// (none, the whole space).
class WithoutSlopeBound final : public ImplicitShape {
public:
  explicit WithoutSlopeBound(const ImplicitShape& shape) : m_shape(shape) {}
  double value(const Eigen::Vector3d& x) const override { return m_shape.value(x); }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override { return m_shape.gradient(x); }
  Eigen::Vector3d center() const override { return m_shape.center(); }
  double bounding_radius() const override { return m_shape.bounding_radius(); }
  Eigen::Vector3d half_extents() const override { return m_shape.half_extents(); }
  double volume() const override { return m_shape.volume(); }
  bool star_shaped() const override { return m_shape.star_shaped(); }
  bool smoothed_indicator() const override { return m_shape.smoothed_indicator(); }

private:
  const ImplicitShape& m_shape;
};

} // namespace

// The slope bound (ImplicitShape::slope_bound) holds between any two points of a line, at the
// kept box's edge too, and is tight: along each voxel axis the largest slope met is the bound.
TEST(LabelShape, SlopeBoundHoldsAlongEveryLineAndIsReachedAlongTheVoxelAxes) {
  for (const double smoothing : {0.0, 0.5, 1.5}) {
    const auto shape = oblique_torus(smoothing);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> coordinate(-25.0, 25.0), unit(-1.0, 1.0), length(0.001, 3.0);
    for (int trial = 0; trial < 20000; ++trial) {
      const Eigen::Vector3d x = Eigen::Vector3d(coordinate(random), coordinate(random), coordinate(random));
      Eigen::Vector3d n(unit(random), unit(random), unit(random));
      if (n.norm() < 1e-3) continue;
      n.normalize();
      const double d = length(random), bound = shape->slope_bound(n);
      ASSERT_TRUE(std::isfinite(bound));
      ASSERT_LE(std::abs(shape->value(x + d * n) - shape->value(x)), bound * d + 1e-12)
          << "smoothing " << smoothing << " at " << x.transpose() << " along " << n.transpose();
    }
    // Along voxel axis a (a world direction), steps of a hundredth of a voxel: the steepest met is
    // the bound, to within the interpolation between centres.
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d n =
          Eigen::Matrix3d(Eigen::AngleAxisd(3.14159265358979 / 6.0, Eigen::Vector3d::UnitZ()))
              .col(a); // the grid's axis a in world space
      const double step = 0.01 * std::array<double, 3>{1.2, 0.8, 1.0}[static_cast<std::size_t>(a)];
      double steepest = 0.0;
      for (int line = 0; line < 400; ++line) {
        const Eigen::Vector3d start(coordinate(random), coordinate(random), 0.5 * coordinate(random));
        for (int s = -3000; s < 3000; ++s) {
          const Eigen::Vector3d x = start + s * step * n;
          steepest = std::max(steepest, std::abs(shape->value(x + step * n) - shape->value(x)) / step);
        }
      }
      EXPECT_GT(steepest, 0.8 * shape->slope_bound(n)) << "smoothing " << smoothing << ", axis " << a;
    }
  }
}

// Skipping the samples the slope bound settles changes nothing: the fit of the same shape with
// and without the bound has the same base vertices and bump amplitudes, bit for bit.
TEST(LabelShape, AFitThatSkipsSettledSamplesIsTheFitThatEvaluatesEveryOne) {
  const auto shape = oblique_torus(0.5);
  ASSERT_FALSE(shape->star_shaped());
  const WithoutSlopeBound plain(*shape);
  PatchFitOptions options;
  options.base_triangles = 320;
  const PatchSurface with =
      fit_patch_surface(*shape, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(), options, "torus");
  const PatchSurface without =
      fit_patch_surface(plain, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(), options, "torus");
  ASSERT_EQ(with.patch_count(), without.patch_count());
  EXPECT_GT(with.patch_count(), 200);
  ASSERT_TRUE(with.base_mesh().vertices == without.base_mesh().vertices);
  int bumps = 0;
  for (Eigen::Index t = 0; t < with.patch_count(); ++t) {
    ASSERT_EQ(with.bumps(t).size(), without.bumps(t).size()) << "patch " << t;
    for (std::size_t b = 0; b < with.bumps(t).size(); ++b) {
      ASSERT_EQ(with.bumps(t)[b].amplitude_mm, without.bumps(t)[b].amplitude_mm)
          << "patch " << t << " bump " << b;
      bumps += with.bumps(t)[b].amplitude_mm != 0.0;
    }
  }
  EXPECT_GT(bumps, 1000); // the fit moved the surface: the comparison is of fitted heights
}

namespace {

/// Trilinear interpolation, computed here, of the shape's values at the eight voxel centres
/// around x (the values at voxel centres are the smoothed labels: the first test).
double trilinear_of_centres(const ImplicitShape& shape, const ImageGrid& grid, const Eigen::Vector3d& x) {
  const Eigen::Matrix3d voxel_from_world = grid.world_from_voxel.topLeftCorner<3, 3>().inverse();
  const Eigen::Vector3d ijk = voxel_from_world * (x - grid.world_from_voxel.topRightCorner<3, 1>());
  const Eigen::Vector3d base = ijk.array().floor(), t = ijk - base;
  double total = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    double weight = 1.0;
    Eigen::Vector3d at;
    for (int a = 0; a < 3; ++a) {
      const int offset = (corner >> a) & 1;
      at[a] = base[a] + offset;
      weight *= offset ? t[a] : 1.0 - t[a];
    }
    total += weight * shape.value(grid.world_from_index(at));
  }
  return total;
}

} // namespace

// value() between voxel centres is the trilinear interpolant of its values at the centres, in
// the kept box's cells and in those that reach past its faces (where the values outside count as
// 0, so -1/2), on a grid whose axes are the world's (x flipped, as an RAS atlas stored LAS) and on
// an oblique one: the axis-aligned shortcut and the bounds test are those of the general formula.
TEST(LabelShape, ValueBetweenVoxelCentresIsTheTrilinearInterpolantInsideAndPastTheKeptBox) {
  for (const bool oblique : {false, true}) {
    SCOPED_TRACE(oblique ? "oblique grid" : "axis-aligned grid");
    ImageGrid grid;
    grid.dims = Eigen::Vector3i(30, 26, 22);
    grid.spacing_mm = Eigen::Vector3d(1.0, 0.9, 1.2);
    Eigen::Matrix3d axes = Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal();
    if (oblique) axes = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    grid.world_from_voxel.setIdentity();
    grid.world_from_voxel.topLeftCorner<3, 3>() = axes * grid.spacing_mm.asDiagonal();
    grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(14.0, -11.5, -12.0);
    // A box of label 1 that the grid's own faces cut on one side (the kept box reaches the grid's
    // edge there) and that leaves room on the others.
    std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
    for (int k = 0; k < 12; ++k)
      for (int j = 6; j < 20; ++j)
        for (int i = 8; i < 22; ++i)
          labels[static_cast<std::size_t>((k * grid.dims.y() + j) * grid.dims.x() + i)] = 1;
    const auto shape = make_label_shape(grid, labels, {1}, 0.8, "box");
    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    int inside = 0, outside = 0;
    for (int n = 0; n < 20000; ++n) {
      Eigen::Vector3d ijk;
      for (int a = 0; a < 3; ++a)
        ijk[a] = -2.0 + (grid.dims[a] + 3.5) * unit(random); // from 2 voxels before to 1.5 past the grid
      const Eigen::Vector3d x = grid.world_from_index(ijk);
      const double value = shape->value(x);
      ASSERT_NEAR(value, trilinear_of_centres(*shape, grid, x), 1e-12)
          << "at voxel coordinates " << ijk.transpose();
      (std::abs(value + 0.5) > 1e-9 ? inside : outside) += 1;
    }
    EXPECT_GT(inside, 2000); // the check reaches the smoothed box, not only the -1/2 around it
    EXPECT_GT(outside, 2000);
  }
}

// Outside the solid box the value is -1/2 (the box holds every point whose cell reaches the kept
// voxels), on an oblique grid and an axis-aligned one; the box is the ball's, not the volume's.
TEST(LabelShape, ValueIsMinusOneHalfOutsideTheSolidBox) {
  for (const bool oblique : {false, true}) {
    SCOPED_TRACE(oblique ? "oblique grid" : "axis-aligned grid");
    ImageGrid grid;
    grid.dims = Eigen::Vector3i(40, 34, 30);
    grid.spacing_mm = Eigen::Vector3d(1.0, 0.9, 1.2);
    grid.world_from_voxel.setIdentity();
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    if (oblique)
      axes = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
    grid.world_from_voxel.topLeftCorner<3, 3>() = axes * grid.spacing_mm.asDiagonal();
    std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
    std::size_t index = 0;
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i, ++index)
          if (std::hypot(i - 22.0, j - 15.0, 1.3 * (k - 14.0)) < 6.0) labels[index] = 2;
    const auto shape = make_label_shape(grid, labels, {2}, 0.8, "ball");
    const Eigen::AlignedBox3d box = shape->solid_box();
    ASSERT_TRUE(box.sizes().allFinite());
    Eigen::AlignedBox3d volume_box; // the whole volume's
    for (int corner = 0; corner < 8; ++corner)
      volume_box.extend(grid.world_from_index(Eigen::Vector3d((corner & 1) ? grid.dims.x() : -1,
                                                              (corner & 2) ? grid.dims.y() : -1,
                                                              (corner & 4) ? grid.dims.z() : -1)));
    EXPECT_LT(box.volume(), 0.3 * volume_box.volume()); // the ball's, with its kernel's reach
    std::mt19937 random(5);
    std::uniform_real_distribution<double> coordinate(-30.0, 70.0);
    int outside = 0, not_outside = 0;
    for (int trial = 0; trial < 200000; ++trial) {
      const Eigen::Vector3d x(coordinate(random), coordinate(random), coordinate(random));
      const double v = shape->value(x);
      if (!box.contains(x)) {
        ASSERT_EQ(v, -0.5) << x.transpose();
        ++outside;
      } else {
        not_outside += v != -0.5;
      }
    }
    EXPECT_GT(outside, 1000);
    EXPECT_GT(not_outside, 10);
  }
}

// TargetBoundary evaluates its lattice within the solid box only: the crossings it finds, and so
// every distance, are those of the whole lattice (the shape wrapped without its box).
TEST(LabelShape, TargetBoundaryWithinTheSolidBoxIsTheWholeLattices) {
  const auto shape = oblique_torus(0.5);
  const WithoutSlopeBound whole(*shape); // no solid box either: the whole space
  ASSERT_FALSE(whole.solid_box().sizes().allFinite());
  const TargetBoundary within(*shape), everywhere(whole);
  ASSERT_GT(within.point_count(), 1000u);
  ASSERT_EQ(within.point_count(), everywhere.point_count());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-25.0, 25.0);
  for (int trial = 0; trial < 5000; ++trial) {
    const Eigen::Vector3d x(coordinate(random), coordinate(random), coordinate(random));
    ASSERT_EQ(within.distance(x), everywhere.distance(x)) << x.transpose();
  }
}
