// The head's tissues outside the brain derived from a T1-weighted scan (docs/anatomy-colin27.md,
// Method): outer CSF, skull with its marrow, and the scalp with its skin, subcutaneous fat and
// muscle. The Colin 27 head (atlas/colin27_head.hpp) and a segmentation's head
// (`anatomy.segmentation` with `t1`, atlas/atlas_labels.hpp) call the same code.
#pragma once

#include "atlas/colin27_head.hpp"

#include <cstdint>
#include <functional>
#include <vector>

namespace phantasm {

/// What derive_extracranial_tissues() found.
struct ExtracranialTissues {
  /// per voxel: colin27_csf (outer CSF), colin27_skull, colin27_bone_marrow, colin27_scalp (the
  /// skin), colin27_subcutaneous_fat, colin27_muscle (and whatever the hook labels); 0 in the
  /// brain and outside the head
  std::vector<std::int32_t> labels;
  int head_threshold = 0;         ///< Otsu's threshold of the T1's levels: the head's outline
  double white_matter_mean = 0.0; ///< the mean T1 level of the white-matter mask
};

/// The T1's values as the levels 0..255 the method thresholds: values already in [0, 255] are
/// rounded (an 8-bit scan such as ch2.nii.gz keeps its values), others are scaled so that the
/// 99.5th percentile of the positive values is 255 (then clamped to 0..255).
std::vector<int> t1_levels(const std::vector<double>& values);

/// Derives the tissues outside the brain from a T1 (levels from t1_levels on `grid`), the brain
/// mask and the brain's white-matter mask (its mean is the reference level of fat and marrow),
/// with the parameters of `options` that concern them (outer_csf_thickness_mm, scalp_thickness_mm,
/// skull_min_thickness_mm, bone_intensity_fraction, skin_thickness_mm, fat_intensity_fraction,
/// marrow_intensity_fraction, majority_filter_passes). Deterministic.
/// @param before_marrow when given, called with the labels after fat and muscle and before the
///        marrow (the Colin head takes its eyes out of skull, fat and muscle there)
ExtracranialTissues derive_extracranial_tissues(
    const ImageGrid& grid, const std::vector<int>& t1, const std::vector<std::uint8_t>& brain,
    const std::vector<std::uint8_t>& white_matter, const Colin27Options& options,
    const std::function<void(double white_matter_mean, std::vector<std::int32_t>& labels)>& before_marrow =
        {});

} // namespace phantasm
