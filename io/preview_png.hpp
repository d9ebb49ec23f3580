// PNG previews of a volume: its three orthogonal middle slices side by side, for a quick look
// at a run's images.
#pragma once

#include "core/grid.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// Writes a PNG preview of a volume: its three orthogonal middle slices (axial, coronal,
/// sagittal in index space) side by side, grey levels from 0 to the 99.5th percentile of the
/// volume, one pixel per voxel (voxel spacing is not resampled). Atomic, like every output.
void write_preview_png(const std::filesystem::path& path, const ImageGrid& grid,
                       const std::vector<float>& values);

/// PNG bytes of an 8-bit image held in memory (the HTML report embeds them).
/// @param width, height in pixels
/// @param components 1 (grey), 3 (RGB) or 4 (RGBA)
/// @param pixels width * height * components bytes, row 0 the bottom row, components interleaved
/// @throws std::invalid_argument when the sizes disagree
std::string encode_png(int width, int height, int components, const std::vector<unsigned char>& pixels);

} // namespace phantasm
