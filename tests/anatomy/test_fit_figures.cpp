// The fit figures the log reports (mean, 95th percentile and maximum distance of a patch surface to
// the source boundary it was fitted to) against an independent measure: distance maps of the
// source labels (exact Euclidean distance transforms), read at the same surface points.

#include "anatomy/implicit_shape.hpp"
#include "anatomy/patch_fit.hpp"
#include "anatomy/phantom.hpp"
#include "geometry/distance_transform.hpp"

#include "tests/support/centred_grid.hpp"
#include <Eigen/LU>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace phantasm;

namespace {

/// Label 1 on a ball of radius 16 mm at the origin, with a cylindrical bore of radius 5 mm along
/// x (not star-shaped: rays from the centre leave it more than once), shifted by `shift_mm`.
std::vector<std::int32_t> bored_ball(const ImageGrid& grid, const Eigen::Vector3d& shift_mm) {
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k)) - shift_mm;
        const bool ball = x.norm() <= 16.0, bore = std::hypot(x.y(), x.z() - 4.0) <= 5.0;
        labels[static_cast<std::size_t>((k * grid.dims.y() + j) * grid.dims.x() + i)] = ball && !bore;
      }
  return labels;
}

/// The independent measure: the distance of x to the labels' boundary (the faces between a
/// labelled and an unlabelled voxel), from the exact distance transforms of both sides: each
/// voxel centre lies its distance to the nearest voxel of the other side, less half a voxel, from
/// the faces; signed (positive inside), read at x by trilinear interpolation.
class LabelBoundaryDistance {
public:
  LabelBoundaryDistance(const ImageGrid& grid, const std::vector<std::int32_t>& labels) : m_grid(grid) {
    std::vector<bool> in(labels.size()), out(labels.size());
    for (std::size_t v = 0; v < labels.size(); ++v) {
      in[v] = labels[v] == 1;
      out[v] = !in[v];
    }
    const std::vector<double> to_in = distance_to(in, grid), to_out = distance_to(out, grid);
    m_face.resize(labels.size());
    for (std::size_t v = 0; v < labels.size(); ++v)
      m_face[v] = in[v] ? to_out[v] - 0.5 : 0.5 - to_in[v]; // signed: positive inside
  }
  double operator()(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d ijk = m_grid.world_from_voxel.inverse().topLeftCorner<3, 3>() * x +
                                m_grid.world_from_voxel.inverse().topRightCorner<3, 1>();
    const Eigen::Vector3d base = ijk.array().floor();
    double total = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      double weight = 1.0;
      Eigen::Vector3i at;
      for (int a = 0; a < 3; ++a) {
        const int offset = (corner >> a) & 1;
        at[a] = std::clamp(static_cast<int>(base[a]) + offset, 0, m_grid.dims[a] - 1);
        weight *= offset ? ijk[a] - base[a] : 1.0 - (ijk[a] - base[a]);
      }
      total +=
          weight *
          m_face[static_cast<std::size_t>((at.z() * m_grid.dims.y() + at.y()) * m_grid.dims.x() + at.x())];
    }
    return std::abs(total);
  }

private:
  ImageGrid m_grid;
  std::vector<double> m_face;
};

struct Figures {
  double mean = 0.0, p95 = 0.0, max = 0.0;
};

Figures figures_of(std::vector<double> d) {
  Figures f;
  for (double v : d)
    f.mean += v;
  f.mean /= static_cast<double>(d.size());
  const auto p95 = d.begin() + static_cast<std::ptrdiff_t>(0.95 * double(d.size() - 1));
  std::nth_element(d.begin(), p95, d.end());
  f.p95 = *p95;
  f.max = *std::max_element(p95, d.end());
  return f;
}

/// The surface's sample points as measure_source_fit takes them (every patch's grid of `level`).
std::vector<Eigen::Vector3d> sample_points(const PatchSurface& surface, int level) {
  std::vector<Eigen::Vector3d> points;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t)
    for (const Eigen::Vector3d& p : surface.patch_grid_points(t, level))
      points.push_back(p);
  return points;
}

} // namespace

// A surface fitted to the labels' smoothed indicator, measured against that source, and the same
// surface measured against the labels shifted by 3 mm (a surface 3 mm off in places): each time
// the reported mean, 95th percentile and maximum lie within a voxel of the distance maps' figures.
TEST(FitFigures, DistanceToTheSourceAgreesWithTheLabelsDistanceMapsWithinAVoxel) {
  const ImageGrid grid = phantasm::testing::centred_cube_grid(48);
  const std::vector<std::int32_t> labels = bored_ball(grid, Eigen::Vector3d::Zero());
  const auto target = make_label_shape(grid, labels, {1}, 1.0, "bored ball");
  ASSERT_FALSE(target->star_shaped());
  PatchFitOptions options;
  options.base_triangles = 500;
  const PatchSurface surface =
      fit_patch_surface(*target, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(), options, "bored ball");
  const int level = 2;

  const std::vector<std::int32_t> shifted = bored_ball(grid, Eigen::Vector3d(3.0, 0.0, 0.0));
  const auto shifted_target = make_label_shape(grid, shifted, {1}, 1.0, "shifted bored ball");
  std::vector<SourceFit> reports;
  for (const auto& [source, source_labels] :
       {std::pair{target.get(), &labels}, std::pair{shifted_target.get(), &shifted}}) {
    reports.push_back(measure_source_fit(surface, *source, level));
    const SourceFit& report = reports.back();
    const LabelBoundaryDistance independent(grid, *source_labels);
    std::vector<double> d;
    for (const Eigen::Vector3d& p : sample_points(surface, level))
      d.push_back(independent(p));
    const Figures f = figures_of(d);
    std::printf("reported mean %.3f p95 %.3f max %.3f mm; distance maps mean %.3f p95 %.3f max %.3f mm\n",
                report.source_mean_mm, report.source_p95_mm, report.source_max_mm, f.mean, f.p95, f.max);
    EXPECT_NEAR(report.source_mean_mm, f.mean, 1.0);
    EXPECT_NEAR(report.source_p95_mm, f.p95, 1.0);
    EXPECT_NEAR(report.source_max_mm, f.max, 1.0);
    EXPECT_LE(report.source_mean_mm, report.source_p95_mm);
    EXPECT_LE(report.source_p95_mm, report.source_max_mm);
  }
  // The fit itself is close to its source; the shifted source is about 3 mm away at its far side.
  const SourceFit &own = reports[0], &off = reports[1];
  EXPECT_LT(own.source_mean_mm, 0.5);
  EXPECT_GT(off.source_max_mm, 2.0);
  EXPECT_GT(off.source_mean_mm, 3.0 * own.source_mean_mm);
}

// The lattice covers a framed shape's own box, rotated: a long box-like superquadric turned 45
// degrees about z reaches 35.4 mm along x and y, far beyond its unrotated radii in y, and its
// surface is found everywhere: the distances beyond its ends and beside its sides are the
// closed-form ones.
TEST(FitFigures, TargetBoundaryCoversARotatedElongatedSuperquadric) {
  const double c = std::sqrt(0.5);
  Eigen::Matrix3d turn;
  turn << c, -c, 0, c, c, 0, 0, 0, 1;
  const Eigen::Vector3d center(3.0, -1.0, 2.0);
  // Exponents 0.1: nearly the box of half sizes 40 x 10 x 10 (its edges rounded by a few %).
  const auto bar = make_superquadric(center, Eigen::Vector3d(40.0, 10.0, 10.0), 0.1, 0.1, turn);
  EXPECT_NEAR(bar->half_extents().x(), 50.0 * c, 1e-12);
  EXPECT_NEAR(bar->half_extents().y(), 50.0 * c, 1e-12);
  EXPECT_NEAR(bar->half_extents().z(), 10.0, 1e-12);
  const TargetBoundary boundary(*bar);
  // 2 mm beyond each end's face along the bar's axis, 3 mm beside its sides, 2 mm above its top.
  const Eigen::Vector3d axis = turn.col(0), across = turn.col(1);
  EXPECT_NEAR(boundary.distance(center + 42.0 * axis), 2.0, 0.25);
  EXPECT_NEAR(boundary.distance(center - 42.0 * axis), 2.0, 0.25);
  EXPECT_NEAR(boundary.distance(center + 13.0 * across), 3.0, 0.25);
  EXPECT_NEAR(boundary.distance(center - 25.0 * axis - 13.0 * across), 3.0, 0.25);
  EXPECT_NEAR(boundary.distance(center + 30.0 * axis + 12.0 * Eigen::Vector3d::UnitZ()), 2.0, 0.25);
}

// The boundary points lie on the target's zero level, and the distance of a point on a sphere's
// normal line is its distance to the sphere, near and far.
TEST(FitFigures, TargetBoundaryMeasuresASphereExactly) {
  const auto ball = make_ellipsoid(Eigen::Vector3d(1.0, -2.0, 0.5), Eigen::Vector3d::Constant(20.0),
                                   Eigen::Matrix3d::Identity());
  const TargetBoundary boundary(*ball);
  EXPECT_GT(boundary.point_count(), 1000u);
  EXPECT_LE(boundary.spacing_mm(), 1.0);
  for (const double r : {20.0, 20.3, 19.6, 25.0, 12.0, 40.0}) {
    for (const Eigen::Vector3d& direction :
         {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.3, -0.5, 0.8).normalized(),
          Eigen::Vector3d(0, 0, -1)}) {
      const Eigen::Vector3d x = Eigen::Vector3d(1.0, -2.0, 0.5) + r * direction;
      EXPECT_NEAR(boundary.distance(x), std::abs(r - 20.0), 0.05) << "r " << r;
    }
  }
}
