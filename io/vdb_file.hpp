// Writing one state's grids to an OpenVDB file: every organ's level set and the label and
// fraction volumes as sparse grids.
#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace phantasm {

/// The grids of one state, for a .vdb file.
struct VdbContents {
  /// By organ name: an openvdb::FloatGrid (LevelSet::grid()), written as "<organ>_sdf". Opaque,
  /// so that io writes level sets without linking the voxelizer that makes them.
  std::vector<std::pair<std::string, const void*>> level_sets;
  const ImageGrid* grid = nullptr;                                          ///< of the dense volumes
  const std::vector<std::int32_t>* labels = nullptr;                        ///< "labels" (Int32Grid)
  std::vector<std::pair<std::string, const std::vector<float>*>> fractions; ///< "fraction_<tissue>"
};

/// Writes an OpenVDB file (atomically: a temporary file, then rename): every organ's level set
/// as it is (world RAS mm), and the label and fraction volumes as sparse grids on the image
/// grid's transform (zero background, so they store only the object).
void write_vdb(const std::filesystem::path& path, const VdbContents& contents);

} // namespace phantasm
