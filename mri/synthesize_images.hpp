// Synthesis of the MR images of every sequence and state from the voxelized tissue fractions:
// signal equations, bias field, receive coils, k-space acquisition and noise. Entry of the stage.
#pragma once

#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "mri/mr_images.hpp"
#include "mri/mri_settings.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <complex>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace phantasm {

struct KspaceSampling;

/// A k-space acquisition of one coil's complex image (x fastest) in place, with noise of
/// noise_sigma per part of a reconstructed voxel seeded by noise_seed: the former method,
/// reference::acquire_in_kspace (mri/kspace_reference.hpp), which tests and benchmarks compare
/// with KspacePipeline. Both give the same images up to rounding, noise apart (the same
/// statistics, other deviates).
using CoilAcquisition = void (*)(std::vector<std::complex<double>>& image, const KspaceSampling& sampling,
                                 double noise_sigma, std::uint64_t noise_seed);

/// The reference state's part of synthesize_images()'s result: one image per sequence and, with
/// settings.parameter_maps, the state's parameter maps. They are made from the settings, the
/// organ table and the reference volumes alone (the coils are placed and normalized over the
/// reference state's object; each image's bias and noise are seeded by the settings' seed, the
/// sequence's index and the state), so that a caller may keep them for later calls with the
/// same inputs.
struct ReferenceImages {
  std::vector<MrImage> images;       ///< one per sequence of the settings, in their order
  std::optional<ParameterMaps> maps; ///< when settings.parameter_maps
};

/// What synthesize_images() makes besides the settings.
struct SynthesisOptions {
  /// How k-space is acquired: nullptr, through KspacePipeline (the object's transform along the
  /// coils' axis once per image, plans and buffers shared by every coil, sequence and state,
  /// in-plane work one plane at a time); otherwise each coil's complex image by this function.
  CoilAcquisition per_coil = nullptr;
  /// The reference state alone: a deformed state the volumes hold is passed over (its images,
  /// its maps). The report gets the same lines as when both are made.
  bool reference_only = false;
  /// The reference state's images and maps as an earlier call with the same settings, organs and
  /// reference volumes made them: taken as they are (the images' sequences pointed at these
  /// settings), so that only the deformed state is synthesized. The report gets the same lines as
  /// when they are made. Their counts and sizes must match the settings and the grid.
  std::optional<ReferenceImages> reference;
};

/// MR images of every sequence of the settings, for each state the volumes hold: each voxel's
/// signal is the fraction-weighted sum of its tissues' signed closed-form signals (so partial
/// volume can cancel at an inversion null), times a smooth multiplicative bias field (a seeded
/// linear ramp spanning bias_percent peak to peak over the object), times each receive coil's
/// sensitivity; with acquisition.kspace the object on the grid is transformed, truncated to the
/// acquired matrix (and slice profile) and reconstructed on the grid by zero filling; complex
/// Gaussian noise of sigma = noise_percent / 100 x the reference tissue's signal per coil (in
/// k-space when it is simulated); the image is the magnitude (Rician), or the sum of squares of
/// several coils. Noise and bias are seeded from settings.seed, the sequence and the state;
/// the result does not depend on the number of threads. Parameter maps come with the images.
/// The images point at settings.sequences: keep the settings alive.
/// @param settings field strength, tissue values, sequences, acquisition, seed, parameter maps
/// @param organs the organ table (the tissues whose parameters are resolved)
/// @param options which states are made, and how k-space is acquired
/// @throws std::invalid_argument when options.reference does not match the settings and the grid
MrImages synthesize_images(const MriSettings& settings, const OrganTable& organs,
                           const VoxelizedPhantom& volumes, StageReport& report, Reporter& reporter,
                           SynthesisOptions options);

/// synthesize_images() of every state the volumes hold.
/// @param per_coil how k-space is acquired (SynthesisOptions::per_coil; benchmarks compare the two)
inline MrImages synthesize_images(const MriSettings& settings, const OrganTable& organs,
                                  const VoxelizedPhantom& volumes, StageReport& report, Reporter& reporter,
                                  CoilAcquisition per_coil = nullptr) {
  SynthesisOptions options;
  options.per_coil = per_coil;
  return synthesize_images(settings, organs, volumes, report, reporter, std::move(options));
}

} // namespace phantasm
