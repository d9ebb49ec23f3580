// A segmentation with a T1 of the same subject (`anatomy.segmentation` with `t1`,
// docs/scene-format.md): the atlas name under which the scene names its derived head, and the
// check that the T1 covers the labels. The scene parser (which refuses bad input at load) and the
// atlas library (which derives the head at run time, atlas/atlas_labels.hpp) share them.
#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// The atlas name of a segmentation's head: "segmentation:LABELS|t1:T1".
std::string segmentation_atlas_name(const std::filesystem::path& labels, const std::filesystem::path& t1);

/// Whether `atlas` is a segmentation's head (segmentation_atlas_name), with its two files.
bool is_segmentation_atlas(const std::string& atlas, std::filesystem::path* labels = nullptr,
                           std::filesystem::path* t1 = nullptr);

/// Throws InputError naming both files unless the T1's grid holds the centre of every labelled
/// voxel (label other than 0) of the label volume, within half a T1 voxel, in world space (RAS mm).
void check_t1_covers_labels(const std::filesystem::path& labels_file, const ImageGrid& label_grid,
                            const std::vector<std::int32_t>& labels, const std::filesystem::path& t1_file,
                            const ImageGrid& t1_grid);

} // namespace phantasm
