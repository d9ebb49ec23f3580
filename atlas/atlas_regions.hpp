// Atlas regions that growth loads name (`{type: growth, region: Hippocampus_L, atlas: aal}`):
// a parcellation in the space of the Colin 27 head, read from installed data.
#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace phantasm {

/// A parcellation: labels on a voxel grid in world space, with the name of each label.
struct AtlasRegions {
  ImageGrid grid;                                         ///< the atlas's grid (Colin 27 space)
  std::vector<std::int32_t> labels;                       ///< grid.voxel_count() labels, i fastest
  std::map<std::string, std::int32_t> regions;            ///< label by region name
  std::map<std::string, std::vector<std::string>> groups; ///< named sets of regions
  std::string source;                                     ///< the files read, for messages
  std::vector<std::string> provenance;                    ///< inputs with their SHA-256, citation
};

/// The region atlases a scene may name ("aal").
std::vector<std::string> region_atlas_names();

/// Reads a region atlas. "aal": aal.nii.gz and its label names aal.nii.txt (lines "label name
/// code") of Debian's mricron-data, in the Colin 27 space (the head of `atlas: colin27`), with
/// the groups: each bilateral pair by its name without the side ("Hippocampus":
/// Hippocampus_L and Hippocampus_R) and "cortex", the cerebral cortex (labels 1-90 but the
/// hippocampi, amygdalae and deep nuclei: caudate, putamen, pallidum, thalamus).
/// @throws InputError for an unknown atlas, a missing or unreadable file (naming the package),
///   or a names file whose lines are not "label name code"
AtlasRegions read_atlas_regions(const std::string& atlas, const std::filesystem::path& templates_dir);

} // namespace phantasm
