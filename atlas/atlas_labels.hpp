// Label volumes that scenes name by atlas (`shape: {type: label_volume, atlas: colin27, ...}`),
// derived at run time from installed data: nothing derived is stored in the repository.
#pragma once

#include "atlas/colin27_head.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// A label volume derived from an atlas, with what a run's log and provenance say about it.
struct AtlasLabels {
  HeadLabels head;                     ///< grid, labels and label table (names)
  std::string source;                  ///< e.g. "atlas colin27 (/usr/share/mricron/templates)"
  std::vector<std::string> provenance; ///< inputs with their SHA-256, the result's hash, citations, time
};

/// The atlases a scene may name.
std::vector<std::string> atlas_names();

/// The names of the labels a segmentation's head adds to those of its label volume (their numbers
/// follow the volume's largest label, in this order): outer_csf, scalp (the skin), subcutaneous_fat,
/// muscle, skull, bone_marrow.
std::vector<std::string> segmentation_head_label_names();

/// A segmentation's head: the label volume `labels` (its numbers kept, resampled nearest onto the
/// T1's grid in world space) with the tissues outside its brain derived from the same subject's T1
/// by the Colin head's method and parameters (derive_extracranial_tissues, docs/anatomy-colin27.md):
/// the brain mask is the union of the volume's labels, holes filled (background inside it becomes
/// outer_csf); the white-matter mask is the T1's brightest class in it (as for the Colin head).
/// No eyes: the Colin head finds them in boxes of the template's MNI space. Padded by two
/// background voxels like the Colin head. Deterministic.
/// @throws InputError naming both files when the T1's grid does not hold every labelled voxel
AtlasLabels derive_segmentation_head(const std::filesystem::path& labels, const std::filesystem::path& t1,
                                     const Colin27Options& options = {});

/// The installed files a named atlas is derived from (for "colin27": ch2.nii.gz, ch2bet.nii.gz and
/// aal.nii.gz in templates_dir; for a segmentation's head its label volume and its T1), in a fixed
/// order.
/// @throws InputError for an unknown atlas
std::vector<std::filesystem::path> atlas_input_files(const std::string& atlas,
                                                     const std::filesystem::path& templates_dir);

/// Derives the label volume of a named atlas (a segmentation's head, io/segmentation.hpp:
/// derive_segmentation_head; "colin27": derive_colin27_head with default options, padded by two background
/// voxels on every side so that labels cut by the template's field of view, the neck, close there; the world
/// positions of the voxels are unchanged). Deterministic.
/// @param atlas an entry of atlas_names()
/// @param templates_dir folder of the installed templates
/// @throws InputError for an unknown atlas or missing templates (naming the package)
AtlasLabels derive_atlas_labels(const std::string& atlas,
                                const std::filesystem::path& templates_dir = default_colin27_templates_dir());

} // namespace phantasm
