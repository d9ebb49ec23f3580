// Images from tissue fractions: Rician noise statistics on an empty background, the bias
// field's span, partial-volume mixing, and seeded repeatability.

#include "mri/parameter_maps.hpp"
#include "mri/receive_coils.hpp"
#include "mri/signal_equations.hpp"
#include "mri/synthesize_images.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

using namespace phantasm;

namespace {

/// One organ of white matter.
OrganTable block() {
  return OrganTable({{"block", "white_matter", ""}});
}

MriSettings noisy_scene(double noise_percent, double bias_percent) {
  MriSettings scene;
  scene.seed = 5;
  scene.field_strength_T = 3.0;
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

/// A 64^3 grid; white matter (label 1) fills the voxels with i < filled_columns, whole.
VoxelizedPhantom volumes(int filled_columns) {
  VoxelizedPhantom v;
  v.grid.dims = {64, 64, 64};
  v.tissues = {"white_matter"};
  const auto count = static_cast<std::size_t>(v.grid.voxel_count());
  v.reference.tissue_count = 1;
  v.reference.label_tissues = {-1, 0};
  v.reference.labels.assign(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    if (static_cast<int>(i % 64) < filled_columns) v.reference.labels[i] = 1;
  }
  return v;
}

} // namespace

// Background of pure noise: magnitude of complex Gaussian noise (Rayleigh), mean
// sigma sqrt(pi/2) and standard deviation sigma sqrt(2 - pi/2).
TEST(SynthesizeImages, BackgroundNoiseHasRayleighMeanAndSpread) {
  const MriSettings scene = noisy_scene(5.0, 0.0);
  StageReport report;
  Reporter quiet = Reporter::silent();
  const MrImages images = synthesize_images(scene, block(), volumes(0), report, quiet);
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
  const double white = sequence_signal(scene.sequences[0], {0.7, 810, 80, 53.2});
  EXPECT_NEAR(sigma, 0.05 * white, 1e-3 * white);
}

TEST(SynthesizeImages, TissueSignalBiasSpanAndSeededRepeatability) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  const MrImages plain = synthesize_images(noisy_scene(0.0, 0.0), block(), volumes(64), report, quiet);
  const double white = sequence_signal(noisy_scene(0, 0).sequences[0], {0.7, 810, 80, 53.2});
  for (float x : plain.reference[0].magnitude)
    ASSERT_NEAR(x, white, 1e-6 * white);
  // A 20 % bias spans 0.9 to 1.1 over the object.
  const MrImages biased = synthesize_images(noisy_scene(0.0, 20.0), block(), volumes(64), report, quiet);
  const auto [low, high] =
      std::minmax_element(biased.reference[0].magnitude.begin(), biased.reference[0].magnitude.end());
  EXPECT_NEAR(*low / white, 0.9, 1e-5);
  EXPECT_NEAR(*high / white, 1.1, 1e-5);
  // Same seed, same bytes; another seed, other noise.
  MriSettings scene = noisy_scene(3.0, 20.0);
  const MrImages a = synthesize_images(scene, block(), volumes(32), report, quiet);
  const MrImages b = synthesize_images(scene, block(), volumes(32), report, quiet);
  EXPECT_EQ(a.reference[0].magnitude, b.reference[0].magnitude);
  scene.seed = 6;
  EXPECT_NE(synthesize_images(scene, block(), volumes(32), report, quiet).reference[0].magnitude,
            a.reference[0].magnitude);
}

// Sum of squares over a ring of coils: without noise the image is the one-coil image times the
// coils' root sum of squares (mean 1 over the object, brighter towards the coils); on an empty
// background it is a chi magnitude with 2 N degrees of freedom, mean sigma sqrt(2) G(N+1/2)/G(N).
TEST(SynthesizeImages, CoilsCombineBySumOfSquares) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  // A cylinder of radius 24 voxels along k in the 64^3 grid.
  VoxelizedPhantom object = volumes(0);
  for (std::size_t v = 0; v < object.reference.labels.size(); ++v) {
    const double x = static_cast<double>(v % 64) - 31.5, y = static_cast<double>((v / 64) % 64) - 31.5;
    if (std::hypot(x, y) < 24.0) object.reference.labels[v] = 1;
  }
  const MrImages one = synthesize_images(noisy_scene(0.0, 0.0), block(), object, report, quiet);
  MriSettings scene = noisy_scene(0.0, 0.0);
  scene.acquisition.coils = 8;
  const MrImages eight = synthesize_images(scene, block(), object, report, quiet);
  EXPECT_EQ(eight.coils, 8);
  std::vector<bool> mask(object.reference.labels.size());
  for (std::size_t v = 0; v < mask.size(); ++v)
    mask[v] = object.reference.background(v) < 0.5f;
  const ReceiveCoils coils(object.grid, 8, mask);
  double ratio_sum = 0.0, low = 1e9, high = 0.0, voxels = 0.0;
  for (std::size_t v = 0; v < mask.size(); ++v) {
    if (!mask[v]) continue;
    const double ratio = eight.reference[0].magnitude[v] / one.reference[0].magnitude[v];
    const double rss = coils.root_sum_of_squares(static_cast<int>(v % 64), static_cast<int>((v / 64) % 64));
    ASSERT_NEAR(ratio, rss, 1e-5 * rss);
    ratio_sum += ratio;
    low = std::min(low, ratio);
    high = std::max(high, ratio);
    voxels += 1.0;
  }
  EXPECT_NEAR(ratio_sum / voxels, 1.0, 1e-5);
  std::cout << "coil shading over the object: " << high / low << "\n";
  EXPECT_GT(high / low, 1.2); // receive arrays are brighter near their elements
  EXPECT_LT(high / low, 4.0);

  MriSettings noisy = noisy_scene(5.0, 0.0);
  const int n = 4;
  noisy.acquisition.coils = n;
  const MrImages background = synthesize_images(noisy, block(), volumes(0), report, quiet);
  const std::vector<float>& m = background.reference[0].magnitude;
  double mean = 0.0;
  for (float x : m)
    mean += x;
  mean /= static_cast<double>(m.size());
  const double sigma = background.reference[0].noise_sigma;
  const double expected = sigma * std::sqrt(2.0) * std::exp(std::lgamma(n + 0.5) - std::lgamma(n));
  EXPECT_NEAR(mean / expected, 1.0, 0.02);
}

// k-space in the image stage: keeping every sample gives the directly sampled image; truncated,
// the background noise is still Rayleigh with the requested sigma, and the report says what was
// modelled.
TEST(SynthesizeImages, KspaceAcquisitionOnTheGrid) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  const VoxelizedPhantom object = volumes(20);
  const MrImages direct = synthesize_images(noisy_scene(0.0, 10.0), block(), object, report, quiet);
  MriSettings scene = noisy_scene(0.0, 10.0);
  scene.acquisition.kspace = true;
  scene.acquisition.kspace_oversampling = 1;
  const MrImages full = synthesize_images(scene, block(), object, report, quiet);
  ASSERT_TRUE(full.kspace);
  EXPECT_TRUE(full.kspace->keeps_everything());
  for (std::size_t v = 0; v < direct.reference[0].magnitude.size(); ++v)
    ASSERT_NEAR(full.reference[0].magnitude[v], direct.reference[0].magnitude[v], 1e-6);

  scene.acquisition.acquired_voxel_mm = Eigen::Vector3d(2.0, 1.0, 4.0);
  scene.acquisition.noise_percent = 5.0;
  StageReport truncated_report;
  const MrImages truncated = synthesize_images(scene, block(), volumes(0), truncated_report, quiet);
  EXPECT_EQ(truncated.kspace->acquired, Eigen::Vector3i(32, 64, 16));
  const std::vector<float>& m = truncated.reference[0].magnitude;
  double mean = 0.0;
  for (float x : m)
    mean += x;
  mean /= static_cast<double>(m.size());
  EXPECT_NEAR(mean / (truncated.reference[0].noise_sigma * std::sqrt(M_PI / 2.0)), 1.0, 0.02);
  bool reported = false;
  for (const std::string& line : truncated_report.modelled)
    reported = reported || line.find("acquired matrix 32x64x16") != std::string::npos;
  EXPECT_TRUE(reported);
}

// Parameter maps: PD adds up over a voxel's tissues, relaxation times are fraction-weighted means
// over the tissue present, and background holds 0. Voxels 0 and 2 are whole (their label's
// tissue, a, and the background), 1 and 3 partial.
TEST(SynthesizeImages, ParameterMapsMixByFraction) {
  const TissueVolumes v = compact_tissue_volumes(
      {1, 1, 0, 0}, {-1, 0},
      {{1.0f, 0.5f, 0.0f, 0.25f}, {0.0f, 0.5f, 0.0f, 0.25f}, {0.0f, 0.0f, 1.0f, 0.5f}});
  ASSERT_EQ(v.partial_voxels, (std::vector<std::size_t>{1, 3}));
  std::map<std::string, TissueParameters> parameters;
  parameters["a"] = {"a", 800.0, 80.0, 60.0, 0.7, "", "", "", ""};
  parameters["b"] = {"b", 1200.0, 100.0, std::nullopt, 0.9, "", "", "", ""};
  const ParameterMaps maps = parameter_maps(v, {"a", "b"}, parameters);
  EXPECT_FLOAT_EQ(maps.PD[0], 0.7f);
  EXPECT_FLOAT_EQ(maps.PD[1], 0.8f);
  EXPECT_FLOAT_EQ(maps.PD[3], 0.4f);
  EXPECT_FLOAT_EQ(maps.T1_ms[1], 1000.0f);
  EXPECT_FLOAT_EQ(maps.T1_ms[3], 1000.0f);
  EXPECT_FLOAT_EQ(maps.T2_ms[1], 90.0f);
  EXPECT_FLOAT_EQ(maps.T2star_ms[1], 60.0f); // b has no T2*: the mean is over a only
  for (const auto* map : {&maps.PD, &maps.T1_ms, &maps.T2_ms, &maps.T2star_ms})
    EXPECT_EQ((*map)[2], 0.0f);
}

// The k-space pipeline against the former per-coil acquisition, 8 coils and a bias field on a
// truncated acquisition with a slice profile: without noise the same images to 1e-5 of the
// brightest voxel (single-precision planes between passes); with noise the same Rayleigh/chi
// statistics on an empty background (other deviates).
TEST(SynthesizeImages, KspacePipelineMatchesThePerCoilAcquisition) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  MriSettings scene = noisy_scene(0.0, 20.0);
  scene.acquisition.kspace = true;
  scene.acquisition.acquired_voxel_mm = Eigen::Vector3d(1.25, 1.5, 2.0);
  scene.acquisition.slice_thickness_mm = 2.0;
  scene.acquisition.coils = 8;
  const VoxelizedPhantom object = volumes(20);
  const MrImages pipeline = synthesize_images(scene, block(), object, report, quiet, KspaceMethod::pipeline);
  const MrImages per_coil = synthesize_images(scene, block(), object, report, quiet, KspaceMethod::per_coil);
  double worst = 0.0, brightest = 0.0;
  for (std::size_t v = 0; v < per_coil.reference[0].magnitude.size(); ++v) {
    worst = std::max(
        worst, double(std::abs(pipeline.reference[0].magnitude[v] - per_coil.reference[0].magnitude[v])));
    brightest = std::max(brightest, double(per_coil.reference[0].magnitude[v]));
  }
  EXPECT_GT(brightest, 0.0);
  EXPECT_LT(worst, 1e-5 * brightest);

  scene.acquisition.noise_percent = 5.0;
  scene.acquisition.bias_percent = 0.0;
  const int n = 8;
  for (KspaceMethod method : {KspaceMethod::pipeline, KspaceMethod::per_coil}) {
    const MrImages background = synthesize_images(scene, block(), volumes(0), report, quiet, method);
    const std::vector<float>& m = background.reference[0].magnitude;
    double mean = 0.0;
    for (float x : m)
      mean += x;
    mean /= static_cast<double>(m.size());
    const double sigma = background.reference[0].noise_sigma;
    const double expected = sigma * std::sqrt(2.0) * std::exp(std::lgamma(n + 0.5) - std::lgamma(n));
    EXPECT_NEAR(mean / expected, 1.0, 0.02);
  }
}
