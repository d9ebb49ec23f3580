// Images from tissue fractions: Rician noise statistics on an empty background, the bias
// field's span, partial-volume mixing, and seeded repeatability.

#include "mri/kspace.hpp"
#include "mri/kspace_reference.hpp"
#include "mri/parameter_maps.hpp"
#include "mri/receive_coils.hpp"
#include "mri/signal_equations.hpp"
#include "mri/synthesize_images.hpp"
#include "mri/texture_signal.hpp"
#include "mri/tissue_parameters.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>

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
  scene.acquisition.receiver_gain = 1.0; // signals in PD units; the gain has a test of its own
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

// The automatic receiver gain puts the reference tissue at the scanner's level (1000) and scales
// the noise with the signal; a gain the scene gives scales the PD-unit image and its noise by
// exactly that factor; a nulled reference tissue gives way to the brightest tissue at 20 000.
TEST(SynthesizeImages, ReceiverGainPutsTheReferenceTissueAtTheScannersLevel) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  MriSettings automatic = noisy_scene(0.0, 0.0);
  automatic.acquisition.receiver_gain.reset();
  const MrImages scanner = synthesize_images(automatic, block(), volumes(64), report, quiet);
  const double white = sequence_signal(automatic.sequences[0], {0.7, 810, 80, 53.2});
  EXPECT_NEAR(scanner.reference[0].receiver_gain, k_receiver_reference_level / white, 1e-9 / white);
  for (float x : scanner.reference[0].magnitude)
    ASSERT_NEAR(x, k_receiver_reference_level, 1e-3);
  EXPECT_NE(std::find_if(report.modelled.begin(), report.modelled.end(),
                         [](const std::string& line) {
                           return line.find("T1w receiver gain") != std::string::npos &&
                                  line.find("automatic: white_matter at 1000") != std::string::npos;
                         }),
            report.modelled.end());

  const MrImages plain = synthesize_images(noisy_scene(3.0, 20.0), block(), volumes(32), report, quiet);
  MriSettings gained = noisy_scene(3.0, 20.0);
  gained.acquisition.receiver_gain = 3e4;
  const MrImages loud = synthesize_images(gained, block(), volumes(32), report, quiet);
  EXPECT_EQ(loud.reference[0].receiver_gain, 3e4);
  EXPECT_NEAR(loud.reference[0].noise_sigma, 3e4 * plain.reference[0].noise_sigma,
              1e-9 * loud.reference[0].noise_sigma);
  for (std::size_t v = 0; v < plain.reference[0].magnitude.size(); ++v)
    ASSERT_NEAR(loud.reference[0].magnitude[v], 3e4 * plain.reference[0].magnitude[v],
                1e-5 * 3e4 * (plain.reference[0].magnitude[v] + white));

  EXPECT_DOUBLE_EQ(automatic_receiver_gain(0.5, 1.0), 2000.0);
  EXPECT_DOUBLE_EQ(automatic_receiver_gain(-0.5, 1.0), 2000.0); // a signed (inverted) signal
  EXPECT_DOUBLE_EQ(automatic_receiver_gain(0.0, 2.0) * 2.0, 20.0 * k_receiver_reference_level);
  EXPECT_DOUBLE_EQ(automatic_receiver_gain(1e-9, 2.0) * 2.0, 20.0 * k_receiver_reference_level);
  EXPECT_EQ(automatic_receiver_gain(0.0, 0.0), 1.0); // no signal at all: nothing to scale
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
  const MrImages pipeline = synthesize_images(scene, block(), object, report, quiet, nullptr);
  const MrImages per_coil =
      synthesize_images(scene, block(), object, report, quiet, &reference::acquire_in_kspace);
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
  for (CoilAcquisition method : {CoilAcquisition(nullptr), &reference::acquire_in_kspace}) {
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

namespace {

/// Two tissues in nested ellipsoids with partial-volume fractions over a voxel at their
/// surfaces, on a grid placed off the origin; the deformed state is the reference shifted by a
/// voxel along i.
VoxelizedPhantom nested_tissues(const Eigen::Vector3i& dims) {
  VoxelizedPhantom v;
  v.grid.dims = dims;
  v.grid.spacing_mm = {1.0, 1.2, 1.5};
  v.grid.world_from_voxel.topLeftCorner<3, 3>() = v.grid.spacing_mm.asDiagonal();
  v.grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-10.0, 5.0, 2.5);
  v.tissues = {"white_matter", "gray_matter"};
  auto state = [&](double shift) {
    const auto count = static_cast<std::size_t>(dims.prod());
    std::vector<std::vector<float>> fractions(3, std::vector<float>(count, 0.0f));
    std::vector<std::int32_t> labels(count, 0);
    for (int k = 0, n = 0; k < dims.z(); ++k)
      for (int j = 0; j < dims.y(); ++j)
        for (int i = 0; i < dims.x(); ++i, ++n) {
          const Eigen::Vector3d x((i - shift - 0.5 * dims.x()) / (0.35 * dims.x()),
                                  (j - 0.5 * dims.y()) / (0.4 * dims.y()),
                                  (k - 0.5 * dims.z()) / (0.3 * dims.z()));
          const double r = x.norm();
          const double outer = std::clamp(0.5 - (r - 1.0) * 0.3 * dims.x(), 0.0, 1.0);
          const double inner = std::clamp(0.5 - (r - 0.6) * 0.3 * dims.x(), 0.0, 1.0);
          const auto u = static_cast<std::size_t>(n);
          fractions[0][u] = static_cast<float>(inner);
          fractions[1][u] = static_cast<float>(outer - inner);
          fractions[2][u] = static_cast<float>(1.0 - outer);
          labels[u] = fractions[2][u] >= 0.5f ? 0 : fractions[0][u] >= fractions[1][u] ? 1 : 2;
        }
    return compact_tissue_volumes(std::move(labels), {-1, 0, 1}, fractions);
  };
  v.reference = state(0.0);
  v.deformed = state(1.0);
  return v;
}

/// The object of one image, as the stage defines it: fraction-weighted tissue signals times a
/// linear bias ramp along a direction drawn from the image's seed, spanning 1 -/+ bias / 200
/// over the voxels that are not mostly background.
std::vector<double> plain_object(const ImageGrid& grid, const TissueVolumes& volumes,
                                 const std::vector<double>& signal, double bias_percent, std::uint64_t seed) {
  const int nx = grid.dims.x(), ny = grid.dims.y();
  std::vector<double> bias(static_cast<std::size_t>(grid.voxel_count()), 1.0);
  std::mt19937_64 random(seed);
  if (bias_percent > 0.0) {
    std::normal_distribution<double> normal;
    Eigen::Vector3d direction(normal(random), normal(random), normal(random));
    direction.normalize();
    const Eigen::Vector3d a = grid.world_from_voxel.topLeftCorner<3, 3>().transpose() * direction;
    const double offset = direction.dot(grid.world_from_voxel.topRightCorner<3, 1>());
    auto along = [&](std::size_t v) {
      const auto i = static_cast<int>(v % nx), j = static_cast<int>(v / nx % ny),
                 k = static_cast<int>(v / nx / ny);
      return a.x() * i + a.y() * j + a.z() * k + offset;
    };
    double low = std::numeric_limits<double>::infinity(), high = -low;
    volumes.for_each_voxel(0, bias.size(), [&](std::size_t v, const float* fractions) {
      if (fractions[signal.size()] >= 0.5f) return;
      low = std::min(low, along(v));
      high = std::max(high, along(v));
    });
    if (high > low)
      for (std::size_t v = 0; v < bias.size(); ++v)
        bias[v] = 1.0 + bias_percent / 200.0 * (2.0 * (along(v) - low) / (high - low) - 1.0);
  }
  std::vector<double> object(bias.size());
  volumes.for_each_voxel(0, object.size(), [&](std::size_t v, const float* fractions) {
    double sum = 0.0;
    for (std::size_t t = 0; t < signal.size(); ++t)
      sum += fractions[t] * signal[t];
    object[v] = sum * bias[v];
  });
  return object;
}

} // namespace

// The stage's k-space images are, byte for byte, the plain composition of the public pieces:
// the object (signals, bias), the receive coils, and the pipeline's sum of squares accumulated
// over the coils in a separate sum and rooted afterwards; two sequences, both states, one and
// three coils, with and without a bias field, on one and two threads.
TEST(SynthesizeImages, KspaceImagesAreThePlainCompositionByteForByte) {
  StageReport report;
  Reporter quiet = Reporter::silent();
  const VoxelizedPhantom object = nested_tissues({20, 18, 14});
  ASSERT_GT(object.reference.partial_voxels.size(), 100u); // partial volume at both surfaces
  const OrganTable organs({{"inner", "white_matter", ""}, {"outer", "gray_matter", ""}});
  const int threads = omp_get_max_threads();
  for (int coils : {1, 3})
    for (double bias : {0.0, 20.0}) {
      MriSettings scene = noisy_scene(3.0, bias);
      SequenceSettings t2;
      t2.name = "T2w";
      t2.kind = SequenceKind::spin_echo;
      t2.TR_ms = 4000;
      t2.TE_ms = 100;
      scene.sequences.push_back(t2);
      scene.acquisition.kspace = true;
      scene.acquisition.acquired_voxel_mm = Eigen::Vector3d(1.25, 1.5, 2.0);
      scene.acquisition.slice_thickness_mm = 2.0;
      scene.acquisition.coils = coils;

      // The plain composition.
      const auto parameters = resolve_tissue_parameters(scene, organs);
      auto signal_of = [&](const SequenceSettings& sequence, const std::string& tissue) {
        const TissueParameters& p = parameters.at(tissue);
        return sequence_signal(sequence, {p.PD.value_or(0.0), p.T1_ms.value_or(1.0), p.T2_ms.value_or(0.0),
                                          p.T2star_ms.value_or(p.T2_ms.value_or(0.0))});
      };
      std::vector<bool> mask(object.reference.labels.size());
      for (std::size_t v = 0; v < mask.size(); ++v)
        mask[v] = object.reference.background(v) < 0.5f;
      const ReceiveCoils ring(object.grid, coils, mask);
      KspaceSampling sampling;
      sampling.dims = object.grid.dims;
      for (int axis = 0; axis < 3; ++axis)
        sampling.acquired[axis] =
            std::clamp(static_cast<int>(std::lround(object.grid.dims[axis] * object.grid.spacing_mm[axis] /
                                                    (*scene.acquisition.acquired_voxel_mm)[axis])),
                       1, object.grid.dims[axis]);
      sampling.slice_thickness_voxels = scene.acquisition.slice_thickness_mm / object.grid.spacing_mm.z();
      KspacePipeline pipeline(sampling, std::min(coils, 2));
      std::vector<std::vector<float>> expected;
      for (std::size_t q = 0; q < scene.sequences.size(); ++q) {
        std::vector<double> signal;
        for (const std::string& tissue : object.tissues)
          signal.push_back(signal_of(scene.sequences[q], tissue));
        const double sigma =
            scene.acquisition.noise_percent / 100.0 *
            std::abs(signal_of(scene.sequences[q], scene.acquisition.noise_reference_tissue));
        for (int state = 0; state < 2; ++state) {
          const std::uint64_t seed = mix_seed(scene.seed, 2 * q + static_cast<std::uint64_t>(state));
          pipeline.set_object(
              plain_object(object.grid, state ? *object.deformed : object.reference, signal, bias, seed));
          std::vector<KspaceCoil> list;
          for (int c = 0; c < coils; ++c)
            list.push_back(
                {ring.sensitivity_plane(c), sigma, mix_seed(seed, static_cast<std::uint64_t>(c) + 1)});
          std::vector<double> energy(mask.size(), 0.0);
          pipeline.add_squared_magnitude(list, energy);
          std::vector<float> magnitude(energy.size());
          for (std::size_t v = 0; v < energy.size(); ++v)
            magnitude[v] = static_cast<float>(std::sqrt(energy[v]));
          expected.push_back(std::move(magnitude));
        }
      }

      for (int t : {1, 2}) {
        omp_set_num_threads(t);
        const MrImages images = synthesize_images(scene, organs, object, report, quiet);
        omp_set_num_threads(threads);
        ASSERT_EQ(images.reference.size(), 2u);
        ASSERT_EQ(images.deformed.size(), 2u);
        for (std::size_t q = 0; q < 2; ++q)
          for (int state = 0; state < 2; ++state) {
            const std::vector<float>& m = (state ? images.deformed : images.reference)[q].magnitude;
            const std::vector<float>& e = expected[2 * q + static_cast<std::size_t>(state)];
            ASSERT_EQ(m.size(), e.size());
            EXPECT_EQ(0, std::memcmp(m.data(), e.data(), m.size() * sizeof(float)))
                << coils << " coils, bias " << bias << ", sequence " << q << ", state " << state << ", " << t
                << " threads";
          }
      }
    }
}

// The parameter maps are, byte for byte, the fraction-weighted mixture of each voxel on its own
// (whole voxels side by side share their arithmetic in the stage): partial volume at two
// surfaces, a tissue without T2*.
TEST(SynthesizeImages, ParameterMapsAreThePlainMixtureByteForByte) {
  const VoxelizedPhantom object = nested_tissues({20, 18, 14});
  std::map<std::string, TissueParameters> parameters;
  parameters["white_matter"] = {"white_matter", 810.0, 80.0, 53.2, 0.7, "", "", "", ""};
  parameters["gray_matter"] = {"gray_matter", 1350.0, 110.0, std::nullopt, 0.8, "", "", "", ""};
  for (const TissueVolumes* volumes : {&object.reference, &*object.deformed}) {
    const ParameterMaps maps = parameter_maps(*volumes, object.tissues, parameters);
    auto plain = [&](std::optional<double> TissueParameters::*member, bool additive) {
      std::vector<float> map(volumes->labels.size(), 0.0f);
      volumes->for_each_voxel(0, map.size(), [&](std::size_t v, const float* fractions) {
        double sum = 0.0, weight = 0.0;
        for (std::size_t t = 0; t < object.tissues.size(); ++t) {
          const std::optional<double> value = parameters.at(object.tissues[t]).*member;
          if (!value) continue;
          sum += fractions[t] * *value;
          weight += fractions[t];
        }
        if (weight > 0.0) map[v] = static_cast<float>(additive ? sum : sum / weight);
      });
      return map;
    };
    const std::pair<const std::vector<float>*, std::vector<float>> cases[] = {
        {&maps.PD, plain(&TissueParameters::PD, true)},
        {&maps.T1_ms, plain(&TissueParameters::T1_ms, false)},
        {&maps.T2_ms, plain(&TissueParameters::T2_ms, false)},
        {&maps.T2star_ms, plain(&TissueParameters::T2star_ms, false)}};
    for (const auto& [map, expected] : cases) {
      ASSERT_EQ(map->size(), expected.size());
      EXPECT_EQ(0, std::memcmp(map->data(), expected.data(), expected.size() * sizeof(float)));
    }
  }
}

// A textured tissue's signal is the signal equation at its voxel's T1 and PD factors, over the
// whole range a scene allows (gain 5 times a deviation of 0.9: T1 factors exp(+-4.5)), not a
// factor clamped to a narrower table while the T1 map holds the exact one.
TEST(TexturedSignal, FollowsTheSignalEquationOverEveryFactorASceneAllows) {
  SequenceSettings spin_echo;
  spin_echo.kind = SequenceKind::spin_echo;
  spin_echo.TR_ms = 500.0;
  spin_echo.TE_ms = 15.0;
  const Relaxation tissue{0.8, 900.0, 80.0, 50.0};
  TextureMaps maps;
  maps.textured = {true};
  const double gain = 1000.0;
  const TexturedSignal textured(spin_echo, {"grey_matter"}, {tissue}, gain, maps);
  ASSERT_TRUE(textured.textured(0));
  for (const double log_factor : {-4.5, -3.0, -1.0, 0.0, 0.7, 2.0, 4.4}) {
    Relaxation r = tissue;
    r.T1_ms *= std::exp(log_factor);
    const double expected = 1.1 * sequence_signal(spin_echo, r) * gain;
    const double got = textured.signal(0, static_cast<float>(std::exp(log_factor)), 1.1f);
    EXPECT_NEAR(got, expected, 2e-3 * std::abs(expected) + 1e-9) << "log T1 factor " << log_factor;
  }
}

namespace {

/// The magnitude signal with T1 x exp(-gain d) and PD x exp(PD_gain d).
double textured_magnitude(const SequenceSettings& sequence, Relaxation r, double gain, double PD_gain,
                          double d) {
  r.T1_ms *= std::exp(-gain * d);
  r.PD *= std::exp(PD_gain * d);
  return std::abs(sequence_signal(sequence, r));
}

} // namespace

// texture.match: the matched T1 gain makes the sequence's signal change by d for a deviation d
// (its slope in d is 1 at d = 0), whichever way T1 moves the signal; where the signal hardly
// follows T1 the gain is held at the largest and says so; a tissue without signal has none.
TEST(TexturedSignal, MatchedT1GainGivesTheSignalTheDeviation) {
  SequenceSettings mprage;
  mprage.kind = SequenceKind::mprage;
  mprage.TR_ms = 2300.0;
  mprage.TI_ms = 900.0;
  mprage.TE_ms = 2.98;
  mprage.flip_deg = 9.0;
  mprage.echo_spacing_ms = 7.1;
  mprage.turbo_factor = 176;
  SequenceSettings spin_echo;
  spin_echo.kind = SequenceKind::spin_echo;
  spin_echo.TR_ms = 4000.0;
  spin_echo.TE_ms = 100.0;
  SequenceSettings flair;
  flair.kind = SequenceKind::inversion_recovery;
  flair.readout = Readout::spin_echo;
  flair.TR_ms = 9000.0;
  flair.TI_ms = 2500.0;
  flair.TE_ms = 120.0;
  const Relaxation white{0.7, 810.0, 80.0, 53.2}, grey{0.83, 1350.0, 110.0, 66.0},
      csf{1.0, 4300.0, 2000.0, 100.0};
  const double PD_gain = 0.25, delta = 1e-3;
  int matched_count = 0;
  for (const SequenceSettings* sequence : {&mprage, &spin_echo, &flair}) {
    for (const Relaxation& tissue : {white, grey, csf}) {
      const std::optional<MatchedT1Gain> m = matched_T1_gain(*sequence, tissue, PD_gain);
      ASSERT_TRUE(m.has_value());
      const double at = textured_magnitude(*sequence, tissue, m->gain, PD_gain, 0.0);
      const double slope = (textured_magnitude(*sequence, tissue, m->gain, PD_gain, delta) -
                            textured_magnitude(*sequence, tissue, m->gain, PD_gain, -delta)) /
                           (2.0 * delta * at);
      if (m->clamped) {
        EXPECT_EQ(std::abs(m->gain), 5.0);
        EXPECT_LT(std::abs(slope), 1.0); // fainter than asked, never the wrong way
        EXPECT_GT(slope, 0.0);
      } else {
        EXPECT_NEAR(slope, 1.0, 1e-4)
            << "T1 " << tissue.T1_ms << " kind " << static_cast<int>(sequence->kind);
        ++matched_count;
      }
    }
  }
  EXPECT_GE(matched_count, 6);
  // MPRAGE: a shorter T1 brightens, and more so than d alone asks: gains below 1 and positive.
  const double g_white = matched_T1_gain(mprage, white, PD_gain)->gain;
  EXPECT_GT(g_white, 0.0);
  EXPECT_LT(g_white, 1.0);
  // CSF read before its null (inversion recovery, TI 1500 ms): still inverted, so a longer T1
  // brightens the magnitude, and the gain is negative.
  SequenceSettings early = flair;
  early.TI_ms = 1500.0;
  const MatchedT1Gain inverted = *matched_T1_gain(early, csf, PD_gain);
  EXPECT_LT(inverted.gain, 0.0);
  EXPECT_FALSE(inverted.clamped);
  EXPECT_NEAR((textured_magnitude(early, csf, inverted.gain, PD_gain, delta) -
               textured_magnitude(early, csf, inverted.gain, PD_gain, -delta)) /
                  (2.0 * delta * textured_magnitude(early, csf, inverted.gain, PD_gain, 0.0)),
              1.0, 1e-4);
  // A long-TR spin echo hardly reads white matter's T1: the gain is held at the largest.
  const std::optional<MatchedT1Gain> held = matched_T1_gain(spin_echo, white, PD_gain);
  ASSERT_TRUE(held.has_value());
  EXPECT_TRUE(held->clamped);
  EXPECT_EQ(held->gain, 5.0);
  const Relaxation none{0.0, 1000.0, 80.0, 50.0};
  EXPECT_FALSE(matched_T1_gain(mprage, none, PD_gain).has_value());
}
