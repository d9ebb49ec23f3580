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

/// The installed files a named atlas is derived from (for "colin27": ch2.nii.gz, ch2bet.nii.gz and
/// aal.nii.gz in templates_dir), in a fixed order.
/// @throws InputError for an unknown atlas
std::vector<std::filesystem::path> atlas_input_files(const std::string& atlas,
                                                     const std::filesystem::path& templates_dir);

/// Derives the label volume of a named atlas ("colin27": derive_colin27_head with default options,
/// padded by two background voxels on every side so that labels cut by the template's field of
/// view, the neck, close there; the world positions of the voxels are unchanged). Deterministic.
/// @param atlas an entry of atlas_names()
/// @param templates_dir folder of the installed templates
/// @throws InputError for an unknown atlas or missing templates (naming the package)
AtlasLabels derive_atlas_labels(const std::string& atlas,
                                const std::filesystem::path& templates_dir = default_colin27_templates_dir());

} // namespace phantasm
