// The MR stage's result: one magnitude image per sequence and state, how they were acquired,
// and the ground-truth parameter maps; the dataset writer reads them.
#pragma once

#include "mri/kspace.hpp"
#include "mri/mri_settings.hpp"

#include <optional>
#include <vector>

// The MR stage's result types, apart from the signal model (mri/synthesize_images.hpp), so that
// the writers include only what they read.

namespace phantasm {

/// Ground-truth quantitative maps of one state on the grid. PD adds up over a voxel's tissues
/// (fraction-weighted sum); T1, T2 and T2* are the fraction-weighted means over the tissues of
/// the voxel that have the value (0 where none has it, e.g. background).
struct ParameterMaps {
  std::vector<float> PD, T1_ms, T2_ms, T2star_ms;
};

/// One magnitude image of one sequence in one state.
struct MrImage {
  const SequenceSettings* sequence = nullptr;
  std::vector<float> magnitude; ///< grid voxel count, in scanner units (PD units x receiver_gain)
  double noise_sigma = 0.0;     ///< std of each of the real and imaginary noise parts (scanner units)
  double receiver_gain = 1.0;   ///< scanner units per proton-density unit
};

struct MrImages {
  std::vector<MrImage> reference;       ///< one per sequence of the settings
  std::vector<MrImage> deformed;        ///< when the phantom was deformed
  std::optional<KspaceSampling> kspace; ///< how the images were acquired, when in k-space
  int coils = 1;                        ///< receive coils combined by sum of squares
  std::optional<ParameterMaps> reference_maps, deformed_maps; ///< when outputs.parameter_maps
};

} // namespace phantasm
