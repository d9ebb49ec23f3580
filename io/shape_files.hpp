// Reading the mesh and label-volume files a scene's organs are made of (and the label volumes
// they name by atlas), by organ name, before the anatomy stage builds them.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "core/grid.hpp"
#include "geometry/shape_data.hpp"

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace phantasm {

/// A label volume a scene names by atlas, as the caller derived it.
struct AtlasLabelVolume {
  ImageGrid grid;
  std::shared_ptr<const std::vector<std::int32_t>> labels; ///< grid.voxel_count() labels, i fastest
  std::map<std::string, std::int32_t> names;               ///< label by name (the atlas's table)
  std::string source;                                      ///< names the atlas in messages
};

/// Derives the label volume of an atlas by name; called once per atlas a scene names.
using AtlasLoader = std::function<AtlasLabelVolume(const std::string& atlas)>;

/// Reads the mesh and label-volume files the organs are made of, by organ name. A label volume
/// used by several organs is read (or derived) once. Each label organ's target is the union of
/// its labels and those of the organs nested in it (`inside`, at any depth) that come from the
/// same volume, so nested surfaces lie inside their container's.
/// @param anatomy the organs
/// @param atlases derives the volumes organs name by atlas; empty: atlases are refused
/// @param scene_grid when given, a label organ's voxels must overlap it
/// @throws SettingError naming the organ's shape key and the file or atlas (unreadable file, no
/// triangles, labels that are not whole numbers, a label absent from its volume or unknown to
/// its atlas, a label touching the volume's edge, labels outside the scene grid)
std::map<std::string, ShapeData> read_shape_files(const AnatomySettings& anatomy,
                                                  const AtlasLoader& atlases = {},
                                                  const std::optional<ImageGrid>& scene_grid = std::nullopt);

} // namespace phantasm
