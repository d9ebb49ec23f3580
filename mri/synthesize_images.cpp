#include "mri/synthesize_images.hpp"

#include "core/format.hpp"
#include "mri/signal_equations.hpp"
#include "mri/tissue_parameters.hpp"

#include <cmath>
#include <random>

namespace phantasm {
namespace {

/// A seed for one image's random numbers: the scene's seed mixed with the sequence and state
/// (splitmix64), so images differ from each other and every run repeats them.
std::uint64_t image_seed(std::uint64_t seed, std::size_t sequence, int state) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (2 * sequence + static_cast<std::uint64_t>(state) + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

MrImage image_of(const Scene& scene, const SequenceSettings& sequence, std::size_t sequence_index, int state,
                 const ImageGrid& grid, const TissueVolumes& volumes,
                 const std::vector<double>& tissue_signal, double reference_signal) {
  MrImage image;
  image.sequence = &sequence;
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  std::vector<double> signal(count, 0.0);
  for (std::size_t t = 0; t < tissue_signal.size(); ++t) {
    const std::vector<float>& f = volumes.fractions[t];
    for (std::size_t v = 0; v < count; ++v)
      signal[v] += f[v] * tissue_signal[t];
  }
  std::mt19937_64 random(image_seed(scene.seed, sequence_index, state));
  // Bias: a linear ramp along a seeded direction, spanning 1 -/+ bias/200 over the object.
  std::vector<double> bias(count, 1.0);
  if (scene.acquisition.bias_percent > 0.0) {
    std::normal_distribution<double> normal;
    Eigen::Vector3d direction(normal(random), normal(random), normal(random));
    direction.normalize();
    double low = std::numeric_limits<double>::infinity(), high = -low;
    std::vector<double> along(count);
    for (int k = 0, v = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i, ++v) {
          along[static_cast<std::size_t>(v)] = direction.dot(grid.world_from_index(Eigen::Vector3d(i, j, k)));
          if (volumes.background[static_cast<std::size_t>(v)] < 0.5) {
            low = std::min(low, along[static_cast<std::size_t>(v)]);
            high = std::max(high, along[static_cast<std::size_t>(v)]);
          }
        }
    if (high > low) {
      const double half_span = scene.acquisition.bias_percent / 200.0;
      for (std::size_t v = 0; v < count; ++v)
        bias[v] = 1.0 + half_span * (2.0 * (along[v] - low) / (high - low) - 1.0);
    }
  }
  image.noise_sigma = scene.acquisition.noise_percent / 100.0 * std::abs(reference_signal);
  std::normal_distribution<double> noise(0.0, image.noise_sigma > 0.0 ? image.noise_sigma : 1.0);
  image.magnitude.resize(count);
  for (std::size_t v = 0; v < count; ++v) {
    double re = signal[v] * bias[v], im = 0.0;
    if (image.noise_sigma > 0.0) {
      re += noise(random);
      im += noise(random);
    }
    image.magnitude[v] = static_cast<float>(std::hypot(re, im));
  }
  return image;
}

} // namespace

MrImages synthesize_images(const Scene& scene, const VoxelizedPhantom& volumes, StageReport& report,
                           Reporter& reporter) {
  MrImages images;
  const auto parameters = resolve_tissue_parameters(scene);
  auto relaxation_of = [&](const std::string& tissue) {
    const TissueParameters& p = parameters.at(tissue);
    // The scene's validation made sure every value a sequence needs is there; others may be empty.
    return Relaxation{p.PD.value_or(0.0), p.T1_ms.value_or(1.0), p.T2_ms.value_or(0.0),
                      p.T2star_ms.value_or(p.T2_ms.value_or(0.0))};
  };
  ProgressBar progress(reporter, "mri", scene.sequences.size() * (volumes.deformed ? 2 : 1));
  for (std::size_t q = 0; q < scene.sequences.size(); ++q) {
    const SequenceSettings& sequence = scene.sequences[q];
    std::vector<double> tissue_signal;
    std::string line = sequence.name + " tissue signals (x PD units):";
    for (const std::string& tissue : volumes.tissues) {
      tissue_signal.push_back(sequence_signal(sequence, relaxation_of(tissue)));
      line += " " + tissue + " " + format_number(tissue_signal.back());
    }
    report.modelled.push_back(line);
    double reference_signal = 0.0;
    const std::string& reference_tissue = scene.acquisition.noise_reference_tissue;
    if (parameters.count(reference_tissue)) {
      reference_signal = sequence_signal(sequence, relaxation_of(reference_tissue));
    } else if (scene.acquisition.noise_percent > 0.0) {
      report.skipped.push_back("noise of " + sequence.name + ": the reference tissue " + reference_tissue +
                               " is not in the phantom");
    }
    images.reference.push_back(
        image_of(scene, sequence, q, 0, volumes.grid, volumes.reference, tissue_signal, reference_signal));
    progress.advance();
    if (volumes.deformed) {
      images.deformed.push_back(
          image_of(scene, sequence, q, 1, volumes.grid, *volumes.deformed, tissue_signal, reference_signal));
      progress.advance();
    }
  }
  if (scene.acquisition.kspace) {
    report.skipped.push_back(
        "k-space simulation: not available in this version; images are sampled directly");
  }
  if (scene.acquisition.coils > 1) {
    report.skipped.push_back("coil sensitivities: not available in this version; one uniform coil");
  }
  report.status = "done";
  return images;
}

} // namespace phantasm
