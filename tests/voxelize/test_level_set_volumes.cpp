// Level sets and partial-volume fractions on analytic shapes: volume from fractions against the
// exact enclosed volume, its convergence under refinement, and the signed-distance property.

#include "anatomy/patch_surface.hpp"
#include "anatomy/triangle_mesh.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/patch_bumps.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/tissue_volumes.hpp"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

/// A fine icosphere scaled to an ellipsoid: the exact volume of the surface the level set is
/// built from is enclosed_volume(mesh).
TriangleMesh ellipsoid_mesh(const Eigen::Vector3d& radii) {
  TriangleMesh mesh = unit_icosphere(6); // 81920 triangles: chord error far below the voxels
  mesh.vertices = mesh.vertices * radii.asDiagonal();
  return mesh;
}

double fraction_volume(const LevelSet& level_set, double voxel_mm, double extent_mm) {
  ImageGrid grid;
  const int n = static_cast<int>(std::ceil(extent_mm / voxel_mm));
  grid.dims = {n, n, n};
  grid.spacing_mm = Eigen::Vector3d::Constant(voxel_mm);
  grid.world_from_voxel.topLeftCorner<3, 3>() = voxel_mm * Eigen::Matrix3d::Identity();
  // Offset by a third of a voxel so the grid is not symmetric about the shape.
  grid.world_from_voxel.topRightCorner<3, 1>() =
      Eigen::Vector3d::Constant(-0.5 * (n - 1) * voxel_mm + voxel_mm / 3.0);
  const VoxelizedOrgan organ{&level_set, 0, 1, 0};
  const TissueVolumes v = voxelize_tissues(grid, {organ}, 1, 4);
  double sum = 0.0;
  for (float f : v.fractions[0])
    sum += f;
  return sum * voxel_mm * voxel_mm * voxel_mm;
}

/// A sphere of radius 20 mm on an 80-triangle base with one round bump per patch, 0.6 mm out
/// and in by turns, 0.8 times as wide as the patch's inscribed circle.
PatchSurface bumpy_sphere() {
  TriangleMesh base = unit_icosphere(1);
  base.vertices *= 20.0;
  PatchSurface surface(base, "bumpy sphere");
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    surface.set_bumps(
        t, {phantasm::testing::disc_in_triangle(base, t, {1.0 / 3.0, 1.0 / 3.0}, 0.8, t % 2 ? -0.6 : 0.6)});
  }
  return surface;
}

} // namespace

// Level sets straight from a patch surface: the fractions' volume against the exact enclosed
// volume (printed beside the tessellated path's), and the distance near zero on the surface.
TEST(PatchLevelSet, FractionsGiveTheVolumeAndTheDistanceIsNearZeroOnTheSurface) {
  const PatchSurface surface = bumpy_sphere();
  const double exact = surface.volume();
  for (double h : {1.0, 0.5}) {
    const LevelSet direct(surface, h);
    const double direct_error = std::abs(fraction_volume(direct, h, 50.0) / exact - 1.0);
    const double tessellated_error =
        std::abs(fraction_volume(LevelSet(surface.tessellate(0.2), h), h, 50.0) / exact - 1.0);
    std::printf("bumpy sphere, voxel %g mm: volume error %.2e direct, %.2e tessellated within 0.2 mm\n", h,
                direct_error, tessellated_error);
    // Bumps a few voxels wide: the trilinear samples of the exact distance round their crests
    // off (measured 1.2e-3 at 1 mm, 2.6e-4 at 0.5 mm; on the head, whose bumps are wider, the
    // error is below the tessellated path's, README).
    EXPECT_LT(direct_error, h > 0.75 ? 2e-3 : 5e-4);
    const LevelSet::Probe probe(direct);
    double worst = 0.0;
    for (Eigen::Index t = 0; t < surface.patch_count(); t += 7)
      for (const Eigen::Vector2d& uv : {Eigen::Vector2d(1.0 / 3.0, 1.0 / 3.0), Eigen::Vector2d(0.4, 0.2)})
        worst = std::max(worst, std::abs(probe(surface.surface_point(t, uv.x(), uv.y()))));
    std::printf("largest |distance| on the surface: %.3f mm\n", worst);
    EXPECT_LT(worst, 0.15 * h);
  }
}

class ShapeVolume : public ::testing::TestWithParam<Eigen::Vector3d> {};

TEST_P(ShapeVolume, FractionsGiveTheVolumeWithinHalfAPercentAtOneMillimetreAndConverge) {
  const Eigen::Vector3d radii = GetParam();
  const TriangleMesh mesh = ellipsoid_mesh(radii);
  const double exact = enclosed_volume(mesh);
  const double extent = 2.0 * radii.maxCoeff() + 8.0;
  std::vector<double> errors;
  for (double h : {2.0, 1.0, 0.5}) {
    const double error = std::abs(fraction_volume(LevelSet(mesh, h), h, extent) / exact - 1.0);
    std::printf("radii (%g, %g, %g) voxel %g mm: relative volume error %.2e\n", radii.x(), radii.y(),
                radii.z(), h, error);
    errors.push_back(error);
  }
  EXPECT_LT(errors[1], 5e-3);
  // Observed order over the two halvings (mean of log2 ratios).
  const double order = 0.5 * (std::log2(errors[0] / errors[1]) + std::log2(errors[1] / errors[2]));
  std::printf("observed order %.2f\n", order);
  EXPECT_GT(order, 1.7); // observed 2.0: the surface error of the sampling falls with h^2
}

INSTANTIATE_TEST_SUITE_P(SphereAndEllipsoid, ShapeVolume,
                         ::testing::Values(Eigen::Vector3d(20, 20, 20), Eigen::Vector3d(24, 17, 12)));

TEST(LevelSet, SignedDistanceGradientHasLengthOneInTheNarrowBand) {
  const TriangleMesh mesh = ellipsoid_mesh({20, 20, 20});
  const LevelSet level_set(mesh, 1.0);
  const LevelSet::Probe probe(level_set);
  const TriangleMesh directions = unit_icosphere(2);
  for (Eigen::Index d = 0; d < directions.vertex_count(); ++d) {
    for (double offset : {-1.5, -0.7, 0.0, 0.6, 1.4}) { // mm from the surface, inside the 3-voxel band
      const Eigen::Vector3d x = (20.0 + offset) * directions.vertex(d);
      const Eigen::Vector3d g = central_difference_gradient(probe, x, 0.5);
      EXPECT_NEAR(g.norm(), 1.0, 0.01) << x.transpose();
      EXPECT_NEAR(probe(x), offset, 0.05) << x.transpose();
    }
  }
  // The band stores the shell within half_width of the surface: about its volume in voxels.
  const double w = level_set.half_width_mm();
  const double shell_voxels = 4.0 / 3.0 * M_PI * (std::pow(20.0 + w, 3) - std::pow(20.0 - w, 3));
  std::printf("narrow band: %zu active voxels, shell of half width %g mm: %.0f voxels\n",
              level_set.active_voxel_count(), w, shell_voxels);
  EXPECT_NEAR(static_cast<double>(level_set.active_voxel_count()) / shell_voxels, 1.0, 0.05);
}

// LevelSet::Probe reads stencils within one leaf straight from it and tiles from one lookup:
// its value must be OpenVDB's own trilinear sample bit for bit, at random points (inside, in the
// band, across leaf boundaries, in tiles deep inside and outside) and on the lattice itself.
TEST(LevelSet, ProbeIsOpenVdbsTrilinearSampleBitForBit) {
  const PatchSurface surface = bumpy_sphere();
  const LevelSet level_set(surface, 0.7);
  const auto& grid = *static_cast<const openvdb::FloatGrid*>(level_set.grid());
  const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
  const LevelSet::Probe probe(level_set);
  std::mt19937 random(17);
  std::uniform_real_distribution<double> coordinate(-30.0, 30.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 200000; ++i)
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; j += 3)
      points.emplace_back(0.7 * i, 0.7 * j, 0.7 * ((i * j) % 17)); // lattice points, leaf edges included
  // Clusters of 4^3 samples a voxel apart, as the tissue fractions take them: most share the
  // previous sample's stencil, which the probe keeps.
  for (int c = 0; c < 3000; ++c) {
    const Eigen::Vector3d centre(coordinate(random), coordinate(random), coordinate(random));
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int d = 0; d < 4; ++d)
          points.push_back(centre + 0.25 * Eigen::Vector3d(a - 1.5, b - 1.5, d - 1.5));
  }
  int in_band = 0;
  for (const Eigen::Vector3d& x : points) {
    const double expected = static_cast<double>(sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())));
    ASSERT_EQ(probe(x), expected) << x.transpose();
    in_band += std::abs(expected) < level_set.half_width_mm();
  }
  EXPECT_GT(in_band, 10000); // the band itself was sampled, not only tiles
}

// Many bumps on every patch, off centre and elongated, as fitted anatomy carries them (there,
// 27 per patch): the level set built from the patches, whose heights sum only the bumps that
// reach the point's cell of the patch, is near zero on the surface, over the crests and between
// them. (A bump left out where it reaches would leave an error of its amplitude, 0.3 to 0.6 mm.)
TEST(PatchLevelSet, ManyBumpsPerPatchAreAllOnTheSurface) {
  TriangleMesh base = unit_icosphere(0);
  base.vertices *= 20.0;
  PatchSurface surface(base, "many bumps");
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<Eigen::Vector2d>> centres(static_cast<std::size_t>(base.face_count()));
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    std::vector<PatchBump> bumps;
    for (int i = 0; i < 16; ++i) {
      // Centres well inside the triangle, radii small enough that the support stays inside.
      double u = 0.0, v = 0.0;
      do {
        u = unit(random);
        v = unit(random);
      } while (u < 0.25 || v < 0.25 || u + v > 0.75);
      const double amplitude = (i % 2 ? -1.0 : 1.0) * (0.3 + 0.3 * unit(random));
      PatchBump bump = disc_in_triangle(base, t, {u, v}, 0.2 + 0.1 * unit(random), amplitude);
      bump.shape_uv(0, 0) *= 1.0 + unit(random); // narrower along u: still inside the disc
      bumps.push_back(bump);
      centres[static_cast<std::size_t>(t)].emplace_back(u, v);
    }
    surface.set_bumps(t, bumps);
  }
  const double h = 0.25;
  const LevelSet level_set(surface, h);
  const LevelSet::Probe probe(level_set);
  double worst = 0.0;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    std::vector<Eigen::Vector2d> uvs = centres[static_cast<std::size_t>(t)];
    for (int i = 0; i < 200; ++i) {
      const double u = unit(random), v = unit(random);
      if (u + v < 1.0) uvs.emplace_back(u, v);
    }
    for (const Eigen::Vector2d& uv : uvs)
      worst = std::max(worst, std::abs(probe(surface.surface_point(t, uv.x(), uv.y()))));
  }
  std::printf("largest |distance| on the surface: %.3f mm\n", worst);
  EXPECT_LT(worst, 0.3 * h);
}

// Outside every box of LevelSet::block_reach_mm a probe reads constant tiles: exactly the band
// width, negative inside. The tissue fractions rely on it to read an organ once per block.
TEST(LevelSet, OutsideEveryBlockReachTheProbeIsTheBandWidth) {
  const PatchSurface surface = bumpy_sphere();
  const LevelSet level_set(surface, 0.7);
  const std::vector<Eigen::AlignedBox3d> reach = level_set.block_reach_mm();
  ASSERT_FALSE(reach.empty());
  const LevelSet::Probe probe(level_set);
  const auto band = static_cast<double>(static_cast<float>(level_set.half_width_mm()));
  std::mt19937 random(5);
  std::uniform_real_distribution<double> coordinate(-30.0, 30.0);
  int inside = 0, outside = 0;
  for (int i = 0; i < 100000; ++i) {
    const Eigen::Vector3d x(coordinate(random), coordinate(random), coordinate(random));
    if (std::any_of(reach.begin(), reach.end(), [&](const Eigen::AlignedBox3d& b) { return b.contains(x); }))
      continue;
    const double value = probe(x);
    ASSERT_EQ(std::abs(value), band) << x.transpose();
    // The side: the sphere's radius is 20 mm, its bumps 0.6 mm high.
    EXPECT_EQ(value < 0.0, x.norm() < 20.0) << x.transpose();
    (value < 0.0 ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 10000);
}

// The deformed state reuses the reference's voxels where no organ differs: an outer organ that
// stays (one level set for both states), an inner one that moves, and the gap it leaves. The
// result must be the bytes of sampling every voxel again, and fewer voxels are sampled.
TEST(TissueFractions, ReusingTheOtherStatesVoxelsGivesTheSameBytes) {
  const auto sphere = [](double radius, const Eigen::Vector3d& centre) {
    TriangleMesh mesh = unit_icosphere(4);
    mesh.vertices = (mesh.vertices * radius).rowwise() + centre.transpose();
    return LevelSet(mesh, 1.0);
  };
  const LevelSet outer = sphere(25.0, Eigen::Vector3d::Zero());
  const LevelSet inner = sphere(6.0, Eigen::Vector3d(-2.0, 0.0, 0.0));
  const LevelSet inner_moved = sphere(6.0, Eigen::Vector3d(2.0, 1.0, 0.0));
  ImageGrid grid;
  grid.dims = {64, 60, 62};
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-31.7, -29.4, -30.5);
  // depth, label, tissue: the outer organ at depth 0, the inner at 2, the gap between them.
  const std::vector<VoxelizedOrgan> reference_organs{{&outer, 0, 1, 0}, {&inner, 2, 2, 1}};
  const std::vector<VoxelizedOrgan> deformed_organs{
      {&outer, 0, 1, 0}, {&inner_moved, 2, 2, 1}, {&inner, 1, 3, 2}};
  const TissueVolumes reference = voxelize_tissues(grid, reference_organs, 3, 4);
  const TissueVolumes fresh = voxelize_tissues(grid, deformed_organs, 3, 4);
  const TissueVolumes reused = voxelize_tissues(grid, deformed_organs, 3, 4, {&reference, &reference_organs});
  EXPECT_EQ(reused.labels, fresh.labels);
  EXPECT_EQ(reused.background, fresh.background);
  EXPECT_EQ(reused.fractions, fresh.fractions);
  EXPECT_NE(fresh.labels, reference.labels); // the inner organ moved and left a gap
  EXPECT_GT(std::count(fresh.labels.begin(), fresh.labels.end(), 3), 100);
  std::printf("voxels sampled: %zu fresh, %zu with the reference's reused\n", fresh.supersampled_voxels,
              reused.supersampled_voxels);
  EXPECT_LT(10 * reused.supersampled_voxels,
            7 * fresh.supersampled_voxels); // most of the outer surface copied
}
