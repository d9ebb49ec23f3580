// Writing one state's grids to an OpenVDB file: every organ's level set and the label and
// fraction volumes as sparse grids, all of grid types that OpenVDB's Python module (pyopenvdb,
// Debian's python3-openvdb: BoolGrid, FloatGrid, Vec3SGrid) reads, so that it opens the whole file.
#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace phantasm {

/// The grids of one state, for a .vdb file.
struct VdbContents {
  /// By organ name: an openvdb::FloatGrid (LevelSet::grid()), written as "<organ>_sdf". Opaque,
  /// so that io writes level sets without linking the voxelizer that makes them.
  std::vector<std::pair<std::string, const void*>> level_sets;
  const ImageGrid* grid = nullptr; ///< of the dense volumes
  /// "labels", a FloatGrid of the dseg label values (exact: labels are small integers)
  const std::vector<std::int32_t>* labels = nullptr;
  /// "fraction_<tissue>": by tissue, what makes its dense fractions (voxel_count() floats), called
  /// when its grid is built, so that one dense volume at a time is held
  std::vector<std::pair<std::string, std::function<std::vector<float>()>>> fractions;
};

/// Writes an OpenVDB file (atomically: a temporary file, then rename): every organ's level set
/// as it is (world RAS mm), and the label and fraction volumes as sparse FloatGrids on the image
/// grid's transform (zero background, so they store only the object). Labels are a FloatGrid, not
/// an Int32Grid, because pyopenvdb cannot read Int32Grid and then refuses the whole file. Each
/// grid carries string metadata "frame" (RAS), "units" and "description".
void write_vdb(const std::filesystem::path& path, const VdbContents& contents);

/// Float grids (openvdb::FloatGrid, opaque as LevelSet::grid() gives them) as bytes, in order,
/// for the reference cache: each tree exactly (its topology and every value, active or not) and
/// the transform; no metadata.
std::string encode_float_grids(const std::vector<const void*>& grids);

/// The grids of encode_float_grids() bytes, in order, each an openvdb::FloatGrid (opaque; a
/// LevelSet is made from it).
/// @throws DamagedBytes (core/byte_codec.hpp) when the bytes do not hold such grids
std::vector<std::shared_ptr<void>> decode_float_grids(std::string_view bytes);

} // namespace phantasm
