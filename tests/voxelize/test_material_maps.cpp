// Volumes attached to the material (voxelize/material_maps.hpp): carried to the deformed state by
// the exact map, tissue regions within an organ, texture from a scan or a random field.
#include "voxelize/material_maps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace phantasm {
namespace {

ImageGrid cube_grid(int n, double spacing) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(n, n, n);
  grid.spacing_mm = Eigen::Vector3d::Constant(spacing);
  grid.world_from_voxel = Eigen::Matrix4d::Identity();
  grid.world_from_voxel.topLeftCorner<3, 3>() *= spacing;
  grid.world_from_voxel.block<3, 1>(0, 3) = Eigen::Vector3d(-10.0, 3.0, 7.5); // off the origin
  return grid;
}

std::size_t voxel_of(const ImageGrid& g, int i, int j, int k) {
  return static_cast<std::size_t>(i + g.dims.x() * (j + g.dims.y() * k));
}

/// A smooth displacement (mm) on the grid, component-major, reaching about 2.5 voxels.
std::vector<float> smooth_field(const ImageGrid& g) {
  const auto count = static_cast<std::size_t>(g.voxel_count());
  std::vector<float> u(3 * count);
  for (int k = 0; k < g.dims.z(); ++k)
    for (int j = 0; j < g.dims.y(); ++j)
      for (int i = 0; i < g.dims.x(); ++i) {
        const Eigen::Vector3d x = g.world_from_index(Eigen::Vector3d(i, j, k));
        const std::size_t v = voxel_of(g, i, j, k);
        u[v] = static_cast<float>(2.0 * std::sin(0.11 * x.y()) + 0.5);
        u[count + v] = static_cast<float>(-1.5 * std::cos(0.07 * x.z()));
        u[2 * count + v] = static_cast<float>(0.04 * x.x());
      }
  return u;
}

// A linear field carried through a displacement equals the field at the displaced points exactly
// (trilinear interpolation reproduces linear functions), wherever the displaced point lies inside
// the grid; outside it the carried value is the given one.
TEST(MaterialMaps, CarriedValuesAreTheReferenceValuesAtTheReferencePositions) {
  const ImageGrid g = cube_grid(24, 1.5);
  const auto count = static_cast<std::size_t>(g.voxel_count());
  auto f = [](const Eigen::Vector3d& x) { return 3.0 + 0.2 * x.x() - 0.1 * x.y() + 0.05 * x.z(); };
  std::vector<float> reference(count);
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i)
        reference[voxel_of(g, i, j, k)] = static_cast<float>(f(g.world_from_index(Eigen::Vector3d(i, j, k))));
  const std::vector<float> u = smooth_field(g);
  const std::vector<float> carried = carry_values(g, reference, u, -99.0f);
  std::size_t inside = 0, outside = 0;
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i) {
        const std::size_t v = voxel_of(g, i, j, k);
        const Eigen::Vector3d at = g.world_from_index(Eigen::Vector3d(i, j, k)) +
                                   Eigen::Vector3d(u[v], u[count + v], u[2 * count + v]);
        const Eigen::Vector3d ijk = g.index_from_world(at);
        if ((ijk.array() >= 0.0).all() && (ijk.array() <= 23.0).all()) {
          EXPECT_NEAR(carried[v], f(at), 1e-4) << i << " " << j << " " << k;
          ++inside;
        } else {
          EXPECT_EQ(carried[v], -99.0f);
          ++outside;
        }
      }
  EXPECT_GT(inside, count / 2);
  EXPECT_GT(outside, 0u);
}

// Labels are carried by the nearest voxel of the displaced point: a ball of label 3 carried by a
// uniform shift of two voxels is the ball shifted the other way, voxel for voxel.
TEST(MaterialMaps, CarriedLabelsMoveWithTheTissue) {
  const ImageGrid g = cube_grid(20, 1.0);
  const auto count = static_cast<std::size_t>(g.voxel_count());
  std::vector<std::int32_t> reference(count, 0);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i)
        if ((Eigen::Vector3d(i, j, k) - Eigen::Vector3d(10, 9, 8)).norm() < 5.0)
          reference[voxel_of(g, i, j, k)] = 3;
  std::vector<float> u(3 * count, 0.0f);
  for (std::size_t v = 0; v < count; ++v) {
    u[v] = 2.0f;              // a deformed point x lies at x + 2 mm (x) in the reference
    u[2 * count + v] = -1.0f; // and at z - 1 mm
  }
  const std::vector<std::int32_t> carried = carry_labels(g, reference, u);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const int ri = i + 2, rk = k - 1;
        const std::int32_t expected =
            ri < 20 && rk >= 0 ? reference[voxel_of(g, ri, j, rk)] : 0; // 0 beyond the grid
        ASSERT_EQ(carried[voxel_of(g, i, j, k)], expected) << i << " " << j << " " << k;
      }
}

// A region relabels only the voxels of its organ that the region volume selects; the organ
// tissue's fraction in a partial voxel becomes the region tissue's, and every voxel's fractions
// still sum to one.
TEST(MaterialMaps, RegionsRelabelTheirOrgansVoxelsAndMoveTheirFractions) {
  // Six voxels, organs 1 (tissue 0) and 2 (tissue 1); voxels 2 and 3 partial.
  std::vector<std::int32_t> labels = {0, 1, 1, 2, 1, 2};
  std::vector<std::vector<float>> fractions = {
      {0, 1, 0.6f, 0.3f, 1, 0}, {0, 0, 0.4f, 0.7f, 0, 1}, {1, 0, 0, 0, 0, 0}};
  TissueVolumes volumes = compact_tissue_volumes(labels, {-1, 0, 1}, fractions);
  ASSERT_EQ(volumes.partial_voxels.size(), 2u);
  widen_tissues(volumes, 3);
  EXPECT_EQ(volumes.tissue_count, 3);
  EXPECT_FLOAT_EQ(volumes.background(0), 1.0f);
  EXPECT_FLOAT_EQ(volumes.fraction(1, 2), 0.4f);
  EXPECT_FLOAT_EQ(volumes.fraction(2, 2), 0.0f);
  // Region value 7 within organ 1 becomes label 5 of tissue 2; value 7 in organ 2 stays.
  const std::vector<std::int32_t> region_volume = {7, 7, 7, 7, 0, 7};
  const std::vector<TissueRegion> regions = {{"marrow", 1, 7, 5, 2, "bone_marrow"}};
  const std::vector<std::size_t> counts = apply_tissue_regions(volumes, region_volume, regions);
  EXPECT_EQ(counts[0], 2u);
  EXPECT_EQ(volumes.labels, (std::vector<std::int32_t>{0, 5, 5, 2, 1, 2}));
  EXPECT_FLOAT_EQ(volumes.fraction(2, 1), 1.0f); // whole voxel of the region
  EXPECT_FLOAT_EQ(volumes.fraction(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(volumes.fraction(2, 2), 0.6f); // the partial voxel's organ share moved
  EXPECT_FLOAT_EQ(volumes.fraction(0, 2), 0.0f);
  EXPECT_FLOAT_EQ(volumes.fraction(1, 2), 0.4f);
  EXPECT_FLOAT_EQ(volumes.fraction(0, 3), 0.3f); // organ 2's voxel keeps its fractions
  EXPECT_FLOAT_EQ(volumes.fraction(0, 4), 1.0f); // organ 1 outside the region
  for (std::size_t v = 0; v < labels.size(); ++v) {
    float sum = volumes.background(v);
    for (int t = 0; t < 3; ++t)
      sum += volumes.fraction(t, v);
    EXPECT_FLOAT_EQ(sum, 1.0f) << v;
  }
}

// The deformed state carries a region where the reference state held it, not wherever the atlas
// labels the region's label: a deformed voxel of the organ whose reference position lies in
// another organ, on a voxel the atlas labels like the region, keeps the organ's label. Along x:
// organ 1 holds region 5 (atlas value 7) at x = 2, 3; the atlas also labels 7 at x = 5, 6, in
// organ 2. The deformed state's organ 1 spans x = 1..5, its points at x + 1 in the reference.
TEST(MaterialMaps, ADeformedRegionIsWhereTheReferenceHeldIt) {
  const ImageGrid g = cube_grid(8, 1.0);
  const auto count = static_cast<std::size_t>(g.voxel_count());
  const std::vector<std::int32_t> reference_along_x = {0, 1, 5, 5, 1, 2, 2, 0};
  const std::vector<std::int32_t> atlas_along_x = {0, 0, 7, 7, 0, 7, 7, 0};
  const std::vector<std::int32_t> deformed_along_x = {0, 1, 1, 1, 1, 1, 2, 0};
  std::vector<std::int32_t> reference(count), atlas(count), deformed(count);
  for (std::size_t v = 0; v < count; ++v) {
    reference[v] = reference_along_x[v % 8];
    atlas[v] = atlas_along_x[v % 8];
    deformed[v] = deformed_along_x[v % 8];
  }
  const std::vector<TissueRegion> regions = {{"marrow", 1, 7, 5, 2, "bone_marrow"}};
  const std::vector<std::int32_t> held = held_region_values(reference, atlas, regions);
  for (std::size_t v = 0; v < count; ++v)
    ASSERT_EQ(held[v], reference[v] == 5 ? 7 : k_no_region) << v;
  std::vector<float> u(3 * count, 0.0f);
  std::fill(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(count), 1.0f); // x + 1 mm
  std::vector<std::vector<float>> fractions(3, std::vector<float>(count, 0.0f));
  for (std::size_t v = 0; v < count; ++v)
    fractions[deformed[v] == 0 ? 2 : static_cast<std::size_t>(deformed[v] - 1)][v] = 1.0f;
  TissueVolumes volumes = compact_tissue_volumes(deformed, {-1, 0, 1}, fractions);
  widen_tissues(volumes, 3);
  TissueVolumes by_atlas = volumes;
  apply_tissue_regions(volumes, carry_labels(g, held, u), regions);
  apply_tissue_regions(by_atlas, carry_labels(g, atlas, u), regions);
  const std::vector<std::int32_t> expected = {0, 5, 5, 1, 1, 1, 2, 0};
  for (std::size_t v = 0; v < count; ++v)
    ASSERT_EQ(volumes.labels[v], expected[v % 8]) << v;
  // Carrying the atlas's labels instead would grow the region where organ 1 moved into organ 2.
  EXPECT_EQ(by_atlas.labels[4], 5);
  EXPECT_EQ(by_atlas.labels[5], 5);
}

// A scan texture gives each textured voxel factors exp(-g1 d) and exp(g2 d) of its deviation d
// from its tissue's mean (clamped); untextured tissues keep factor 1.
TEST(MaterialMaps, ScanTextureFollowsTheWithinTissueDeviation) {
  std::vector<std::int32_t> labels = {1, 1, 1, 1, 2, 2};
  std::vector<std::vector<float>> fractions = {{1, 1, 1, 1, 0, 0}, {0, 0, 0, 0, 1, 1}, {0, 0, 0, 0, 0, 0}};
  const TissueVolumes volumes = compact_tissue_volumes(labels, {-1, 0, 1}, fractions);
  const std::vector<float> intensity = {90, 110, 100, 200, 10, 30}; // tissue 0 mean 125
  const TextureGains gains{1.0, 0.25, 0.3};
  const TextureMaps maps = texture_from_intensity(volumes, {true, false}, intensity, gains);
  const double d0 = 90.0 / 125.0 - 1.0;
  EXPECT_NEAR(maps.T1_factor[0], std::exp(-d0), 1e-6);
  EXPECT_NEAR(maps.PD_factor[0], std::exp(0.25 * d0), 1e-6);
  EXPECT_NEAR(maps.T1_factor[3], std::exp(-0.3), 1e-6); // d = 0.6 clamped to 0.3
  EXPECT_EQ(maps.T1_factor[4], 1.0f);
  EXPECT_EQ(maps.PD_factor[5], 1.0f);
}

// Per-tissue T1 gains (texture.match): each voxel's T1 factor takes its label tissue's gain, the
// PD factor the common PD gain.
TEST(MaterialMaps, EachTissueTakesItsOwnT1Gain) {
  std::vector<std::int32_t> labels = {1, 1, 2, 2};
  std::vector<std::vector<float>> fractions = {{1, 1, 0, 0}, {0, 0, 1, 1}, {0, 0, 0, 0}};
  const TissueVolumes volumes = compact_tissue_volumes(labels, {-1, 0, 1}, fractions);
  const std::vector<float> intensity = {90, 110, 80, 120}; // both tissues' means 100
  TextureGains gains{1.0, 0.25, 0.3};
  gains.T1_gain_by_tissue = {0.5, -2.0};
  const TextureMaps maps = texture_from_intensity(volumes, {true, true}, intensity, gains);
  EXPECT_NEAR(maps.T1_factor[0], std::exp(-0.5 * -0.1), 1e-6);
  EXPECT_NEAR(maps.T1_factor[1], std::exp(-0.5 * 0.1), 1e-6);
  EXPECT_NEAR(maps.T1_factor[2], std::exp(2.0 * -0.2), 1e-6);
  EXPECT_NEAR(maps.T1_factor[3], std::exp(2.0 * 0.2), 1e-6);
  EXPECT_NEAR(maps.PD_factor[3], std::exp(0.25 * 0.2), 1e-6);
}

// A random texture repeats with its seed, changes with another, and has the asked-for spread
// over the textured voxels.
TEST(MaterialMaps, RandomTextureIsSeededWithTheAskedSpread) {
  const ImageGrid g = cube_grid(16, 1.0);
  const auto count = static_cast<std::size_t>(g.voxel_count());
  std::vector<std::int32_t> labels(count, 1);
  std::vector<std::vector<float>> fractions = {std::vector<float>(count, 1.0f),
                                               std::vector<float>(count, 0.0f)};
  const TissueVolumes volumes = compact_tissue_volumes(labels, {-1, 0}, fractions);
  const TextureGains gains{1.0, 0.0, 0.9};
  const TextureMaps a = texture_from_random_field(g, volumes, {true}, 5, 1.5, 0.05, gains);
  const TextureMaps b = texture_from_random_field(g, volumes, {true}, 5, 1.5, 0.05, gains);
  const TextureMaps c = texture_from_random_field(g, volumes, {true}, 6, 1.5, 0.05, gains);
  EXPECT_EQ(a.T1_factor, b.T1_factor);
  EXPECT_NE(a.T1_factor, c.T1_factor);
  double sum = 0.0, squares = 0.0;
  for (float f : a.T1_factor) {
    const double d = -std::log(f);
    sum += d;
    squares += d * d;
  }
  EXPECT_NEAR(sum / count, 0.0, 1e-3);
  EXPECT_NEAR(std::sqrt(squares / count), 0.05, 2e-3);
  for (float f : a.PD_factor)
    ASSERT_EQ(f, 1.0f); // PD gain 0
}

} // namespace
} // namespace phantasm
