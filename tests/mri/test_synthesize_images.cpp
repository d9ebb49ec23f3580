// Images from tissue fractions: Rician noise statistics on an empty background, the bias
// field's span, partial-volume mixing, and seeded repeatability.

#include "mri/signal_equations.hpp"
#include "mri/synthesize_images.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace phantasm;

namespace {

Scene noisy_scene(double noise_percent, double bias_percent) {
  Scene scene;
  scene.seed = 5;
  scene.field_strength_T = 3.0;
  OrganSettings organ;
  organ.name = "block";
  organ.tissue = "white_matter";
  scene.anatomy.organs.push_back(organ);
  SequenceSettings t1;
  t1.name = "T1w";
  t1.kind = SequenceKind::spoiled_gre;
  t1.TR_ms = 20;
  t1.TE_ms = 4;
  t1.flip_deg = 25;
  scene.sequences.push_back(t1);
  scene.acquisition.noise_percent = noise_percent;
  scene.acquisition.noise_reference_tissue = "white_matter";
  scene.acquisition.bias_percent = bias_percent;
  return scene;
}

/// A 64^3 grid; white matter fills the voxels with i < filled_columns.
VoxelizedPhantom volumes(int filled_columns) {
  VoxelizedPhantom v;
  v.grid.dims = {64, 64, 64};
  v.tissues = {"white_matter"};
  const auto count = static_cast<std::size_t>(v.grid.voxel_count());
  v.reference.fractions.assign(1, std::vector<float>(count, 0.0f));
  v.reference.background.assign(count, 1.0f);
  v.reference.labels.assign(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    if (static_cast<int>(i % 64) < filled_columns) {
      v.reference.fractions[0][i] = 1.0f;
      v.reference.background[i] = 0.0f;
    }
  }
  return v;
}

} // namespace

// Background of pure noise: magnitude of complex Gaussian noise (Rayleigh), mean
// sigma sqrt(pi/2) and standard deviation sigma sqrt(2 - pi/2).
TEST(SynthesizeImages, BackgroundNoiseHasRayleighMeanAndSpread) {
  const Scene scene = noisy_scene(5.0, 0.0);
  StageReport report;
  Reporter quiet = Reporter::silent();
  const MrImages images = synthesize_images(scene, volumes(0), report, quiet);
  const std::vector<float>& m = images.reference[0].magnitude;
  const double sigma = images.reference[0].noise_sigma;
  EXPECT_GT(sigma, 0.0);
  double mean = 0.0;
  for (float x : m)
    mean += x;
  mean /= static_cast<double>(m.size());
  double variance = 0.0;
  for (float x : m)
    variance += (x - mean) * (x - mean);
  const double deviation = std::sqrt(variance / static_cast<double>(m.size() - 1));
  EXPECT_NEAR(mean / (sigma * std::sqrt(M_PI / 2.0)), 1.0, 0.02);
  EXPECT_NEAR(deviation / (sigma * std::sqrt(2.0 - M_PI / 2.0)), 1.0, 0.02);
  // sigma is 5 % of white matter's signal.
  const double white = sequence_signal(scene.sequences[0], {0.7, 810, 71, 53.2});
  EXPECT_NEAR(sigma, 0.05 * white, 1e-3 * white);
}

TEST(SynthesizeImages, TissueSignalBiasSpanAndSeededRepeatability) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  const MrImages plain = synthesize_images(noisy_scene(0.0, 0.0), volumes(64), report, quiet);
  const double white = sequence_signal(noisy_scene(0, 0).sequences[0], {0.7, 810, 71, 53.2});
  for (float x : plain.reference[0].magnitude)
    ASSERT_NEAR(x, white, 1e-6 * white);
  // A 20 % bias spans 0.9 to 1.1 over the object.
  const MrImages biased = synthesize_images(noisy_scene(0.0, 20.0), volumes(64), report, quiet);
  const auto [low, high] =
      std::minmax_element(biased.reference[0].magnitude.begin(), biased.reference[0].magnitude.end());
  EXPECT_NEAR(*low / white, 0.9, 1e-5);
  EXPECT_NEAR(*high / white, 1.1, 1e-5);
  // Same seed, same bytes; another seed, other noise.
  Scene scene = noisy_scene(3.0, 20.0);
  const MrImages a = synthesize_images(scene, volumes(32), report, quiet);
  const MrImages b = synthesize_images(scene, volumes(32), report, quiet);
  EXPECT_EQ(a.reference[0].magnitude, b.reference[0].magnitude);
  scene.seed = 6;
  EXPECT_NE(synthesize_images(scene, volumes(32), report, quiet).reference[0].magnitude,
            a.reference[0].magnitude);
}
