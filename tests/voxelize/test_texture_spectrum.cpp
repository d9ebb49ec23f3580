// The texture of a scan measured (voxelize/texture_spectrum.hpp) and drawn again as seeded random
// fields per tissue (texture_from_random_fields, voxelize/material_maps.hpp): a field of known
// spread and correlation is measured back, within a tissue that is not the whole grid, with the
// white noise of a scan told apart from the texture.
#include "voxelize/material_maps.hpp"
#include "voxelize/texture_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace phantasm {
namespace {

ImageGrid spectrum_grid(int n, double spacing) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(n, n, n);
  grid.spacing_mm = Eigen::Vector3d::Constant(spacing);
  grid.world_from_voxel = Eigen::Matrix4d::Identity();
  grid.world_from_voxel.topLeftCorner<3, 3>() *= spacing;
  return grid;
}

/// Volumes whose voxels inside a ball of `radius` voxels about the centre hold tissue 0 (label 1)
/// and whose others hold tissue 1 (label 2); radius 0: tissue 0 everywhere.
TissueVolumes ball_volumes_of(const ImageGrid& g, double radius) {
  const auto count = static_cast<std::size_t>(g.voxel_count());
  std::vector<std::int32_t> labels(count);
  std::vector<std::vector<float>> fractions(3, std::vector<float>(count, 0.0f));
  const double centre = 0.5 * (g.dims.x() - 1);
  for (int k = 0; k < g.dims.z(); ++k)
    for (int j = 0; j < g.dims.y(); ++j)
      for (int i = 0; i < g.dims.x(); ++i) {
        const std::size_t v = voxel_index(g.dims, i, j, k);
        const double r = Eigen::Vector3d(i - centre, j - centre, k - centre).norm();
        const int tissue = radius <= 0.0 || r <= radius ? 0 : 1;
        labels[v] = tissue + 1;
        fractions[static_cast<std::size_t>(tissue)][v] = 1.0f;
      }
  return compact_tissue_volumes(labels, {-1, 0, 1}, fractions);
}

/// The deviation d of each voxel that a texture of T1 gain 1 gives (T1 factor exp(-d)).
std::vector<double> deviations(const TextureMaps& maps) {
  std::vector<double> d(maps.T1_factor.size());
  for (std::size_t v = 0; v < d.size(); ++v)
    d[v] = -std::log(static_cast<double>(maps.T1_factor[v]));
  return d;
}

const TextureGains k_plain{1.0, 0.0, 0.9}; // d itself in the T1 factor, hardly clamped

// A field drawn with spread 0.06 and a 3 mm Gaussian on a 1.5 mm grid is measured back: its
// spread within 5 %, its correlation length within 10 %, no white share.
TEST(TextureSpectrum, DrawnFieldIsMeasuredBack) {
  const ImageGrid g = spectrum_grid(48, 1.5);
  const TissueVolumes volumes = ball_volumes_of(g, 0.0);
  const TextureMaps maps = texture_from_random_fields(g, volumes, {true}, 11, {{0.06, 3.0}}, k_plain);
  std::vector<float> intensity;
  for (double d : deviations(maps))
    intensity.push_back(static_cast<float>(500.0 * (1.0 + d)));
  const std::vector<TextureSpectrum> measured =
      measure_texture_spectra(g, intensity, std::vector<int>(intensity.size(), 0), 1);
  ASSERT_EQ(measured.size(), 1u);
  const TextureSpectrum& s = measured[0];
  std::printf("sd %.4f s %.3f mm amplitude %.3f lags %d\n", s.deviation_sd, s.correlation_mm, s.amplitude,
              s.lags_fitted);
  EXPECT_EQ(s.voxels, intensity.size());
  EXPECT_NEAR(s.mean, 500.0, 1.0);
  EXPECT_NEAR(s.deviation_sd, 0.06, 0.05 * 0.06);
  EXPECT_NEAR(s.correlation_mm, 3.0, 0.1 * 3.0);
  EXPECT_GT(s.amplitude, 0.95);
  EXPECT_NEAR(s.texture_sd, 0.06, 0.05 * 0.06);
  // The autocorrelation falls as the model's: exp(-r^2 / (4 s^2)) at one voxel (1.5 mm).
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_NEAR(s.autocorrelation[axis][0], std::exp(-1.5 * 1.5 / 36.0), 0.03);
}

// Each tissue's field is its own and follows the seed: the same seed gives the same bytes,
// another seed other ones; two tissues' spreads are each their own.
TEST(TextureSpectrum, FieldsPerTissueAreSeeded) {
  const ImageGrid g = spectrum_grid(24, 1.0);
  const TissueVolumes volumes = ball_volumes_of(g, 7.0);
  const std::vector<TextureField> fields = {{0.05, 1.5}, {0.1, 3.0}};
  const TextureMaps a = texture_from_random_fields(g, volumes, {true, true}, 5, fields, k_plain);
  const TextureMaps b = texture_from_random_fields(g, volumes, {true, true}, 5, fields, k_plain);
  const TextureMaps c = texture_from_random_fields(g, volumes, {true, true}, 6, fields, k_plain);
  EXPECT_EQ(a.T1_factor, b.T1_factor);
  EXPECT_EQ(a.PD_factor, b.PD_factor);
  EXPECT_NE(a.T1_factor, c.T1_factor);
  double squares[2] = {0.0, 0.0};
  std::size_t counts[2] = {0, 0};
  const std::vector<double> d = deviations(a);
  for (std::size_t v = 0; v < d.size(); ++v) {
    const auto t = static_cast<std::size_t>(volumes.labels[v] - 1);
    squares[t] += d[v] * d[v];
    ++counts[t];
  }
  EXPECT_NEAR(std::sqrt(squares[0] / counts[0]), 0.05, 1e-3);
  EXPECT_NEAR(std::sqrt(squares[1] / counts[1]), 0.1, 2e-3);
  // An untextured tissue keeps factor 1.
  const TextureMaps only_ball = texture_from_random_fields(g, volumes, {true, false}, 5, fields, k_plain);
  for (std::size_t v = 0; v < d.size(); ++v)
    if (volumes.labels[v] == 2) {
      ASSERT_EQ(only_ball.T1_factor[v], 1.0f);
    }
}

// A small synthetic scan: a ball of one tissue (texture 0.06 at 1.5 mm, plus white noise of
// 0.03, the scan's noise) inside another of other texture (0.1 at 3 mm, intensity three times
// as high). Each tissue's figures are found from its own voxels: the ball's correlation length
// and texture spread (white noise left out) within 10 %, its white share about 0.03^2 / (0.06^2 +
// 0.03^2) = 0.2; the outer tissue's within 10 %.
TEST(TextureSpectrum, ScanTextureIsMeasuredWithinATissueMask) {
  const ImageGrid g = spectrum_grid(56, 1.0);
  const TissueVolumes volumes = ball_volumes_of(g, 22.0);
  const TextureMaps maps =
      texture_from_random_fields(g, volumes, {true, true}, 3, {{0.06, 1.5}, {0.1, 3.0}}, k_plain);
  const std::vector<double> d = deviations(maps);
  std::mt19937_64 random(99);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<float> intensity(d.size());
  std::vector<int> region(d.size());
  for (std::size_t v = 0; v < d.size(); ++v) {
    region[v] = volumes.labels[v] - 1;
    intensity[v] = region[v] == 0 ? static_cast<float>(200.0 * (1.0 + d[v] + noise(random)))
                                  : static_cast<float>(600.0 * (1.0 + d[v]));
  }
  const std::vector<TextureSpectrum> measured = measure_texture_spectra(g, intensity, region, 2);
  ASSERT_EQ(measured.size(), 2u);
  const TextureSpectrum& ball = measured[0];
  const TextureSpectrum& outer = measured[1];
  std::printf("ball: sd %.4f texture sd %.4f s %.3f mm white %.3f; outer: sd %.4f s %.3f mm white %.3f\n",
              ball.deviation_sd, ball.texture_sd, ball.correlation_mm, ball.white_share, outer.deviation_sd,
              outer.correlation_mm, outer.white_share);
  EXPECT_NEAR(ball.mean, 200.0, 2.0);
  EXPECT_NEAR(ball.deviation_sd, std::sqrt(0.06 * 0.06 + 0.03 * 0.03), 0.05 * 0.067);
  EXPECT_NEAR(ball.texture_sd, 0.06, 0.1 * 0.06);
  EXPECT_NEAR(ball.correlation_mm, 1.5, 0.1 * 1.5);
  EXPECT_NEAR(ball.white_share, 0.2, 0.05);
  EXPECT_NEAR(outer.mean, 600.0, 6.0);
  EXPECT_NEAR(outer.deviation_sd, 0.1, 0.05 * 0.1);
  EXPECT_NEAR(outer.correlation_mm, 3.0, 0.1 * 3.0);
  EXPECT_LT(outer.white_share, 0.05);
}

// White noise alone has no texture: no lag correlates, s and the amplitude are 0.
TEST(TextureSpectrum, WhiteNoiseIsNoTexture) {
  const ImageGrid g = spectrum_grid(20, 1.0);
  std::mt19937_64 random(1);
  std::normal_distribution<double> noise(100.0, 5.0);
  std::vector<float> intensity(static_cast<std::size_t>(g.voxel_count()));
  for (float& value : intensity)
    value = static_cast<float>(noise(random));
  const TextureSpectrum s =
      measure_texture_spectra(g, intensity, std::vector<int>(intensity.size(), 0), 1)[0];
  EXPECT_NEAR(s.deviation_sd, 0.05, 0.003);
  EXPECT_EQ(s.lags_fitted, 0);
  EXPECT_EQ(s.correlation_mm, 0.0);
  EXPECT_EQ(s.texture_sd, 0.0);
  EXPECT_EQ(s.white_share, 1.0);
}

// Two tissues of constant intensity (100 and 50) meet in a plane, the voxels on either side of it a
// mix of both (80 and 60), as a scan's partial volume makes them: measured whole, each region's
// border layer counts as texture (sd about 0.05); eroded by one voxel (the default), each
// tissue's deviation is 0. A region too thin to keep a quarter of its voxels is measured whole.
TEST(TextureSpectrum, PartialVolumeAtATissueBorderIsNoTexture) {
  const ImageGrid g = spectrum_grid(32, 1.0);
  const auto count = static_cast<std::size_t>(g.voxel_count());
  std::vector<float> intensity(count);
  std::vector<int> region(count);
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        const std::size_t v = voxel_index(g.dims, i, j, k);
        region[v] = i < 16 ? 0 : 1;
        intensity[v] = i < 15 ? 100.0f : i == 15 ? 80.0f : i == 16 ? 60.0f : 50.0f;
      }
  TextureSpectrumOptions whole;
  whole.erode_voxels = 0;
  const std::vector<TextureSpectrum> raw = measure_texture_spectra(g, intensity, region, 2, whole);
  EXPECT_GT(raw[0].deviation_sd, 0.04);
  EXPECT_GT(raw[1].deviation_sd, 0.04);
  EXPECT_EQ(raw[0].voxels, 16u * 32u * 32u);

  const std::vector<TextureSpectrum> eroded = measure_texture_spectra(g, intensity, region, 2);
  for (const TextureSpectrum& s : eroded) {
    EXPECT_EQ(s.voxels, 15u * 32u * 32u); // the layer at the border, not the grid's edge
    EXPECT_EQ(s.deviation_sd, 0.0);
    EXPECT_EQ(s.texture_sd, 0.0);
  }
  EXPECT_DOUBLE_EQ(eroded[0].mean, 100.0);
  EXPECT_DOUBLE_EQ(eroded[1].mean, 50.0);

  // A slab two voxels thick keeps nothing after one erosion: it is measured whole. (A region
  // eroded to less than a quarter of its voxels would be too.)
  for (std::size_t v = 0; v < count; ++v)
    region[v] = region[v] == 0 && intensity[v] != 80.0f ? 1 : region[v];
  for (std::size_t v = 0; v < count; ++v)
    if (intensity[v] == 60.0f) region[v] = 0;
  TextureSpectrumOptions deep;
  deep.erode_voxels = 3;
  const std::vector<TextureSpectrum> slab = measure_texture_spectra(g, intensity, region, 2, deep);
  EXPECT_EQ(slab[0].voxels, 2u * 32u * 32u);
  EXPECT_NEAR(slab[0].mean, 70.0, 1e-9);

  // A slab three voxels thick keeps its middle third after one erosion: measured there, unless a
  // larger share is asked to stay.
  std::vector<int> three(count);
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i)
        three[voxel_index(g.dims, i, j, k)] = i >= 14 && i <= 16 ? 0 : 1;
  EXPECT_EQ(measure_texture_spectra(g, intensity, three, 2)[0].voxels, 32u * 32u);
  TextureSpectrumOptions half;
  half.min_eroded_share = 0.5;
  EXPECT_EQ(measure_texture_spectra(g, intensity, three, 2, half)[0].voxels, 3u * 32u * 32u);
}

} // namespace
} // namespace phantasm
