// Voxel masks on one grid, shared by the head derivations of the atlas library (the Colin 27
// head, docs/anatomy-colin27.md, and the tissues outside the brain, atlas/extracranial_tissues.hpp):
// distances, connected components, hole filling, thresholds of a T1's histogram. Internal to the
// atlas library.
#pragma once

#include "core/grid.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace phantasm {

struct NiftiVolume;

namespace voxel_masks {

using Mask = std::vector<std::uint8_t>;

/// Index arithmetic on one grid.
struct Volume {
  int nx = 0, ny = 0, nz = 0;
  explicit Volume(const ImageGrid& grid) : nx(grid.dims.x()), ny(grid.dims.y()), nz(grid.dims.z()) {}
  std::int64_t size() const { return std::int64_t(nx) * ny * nz; }
  std::int64_t at(int i, int j, int k) const { return i + std::int64_t(nx) * (j + std::int64_t(ny) * k); }
};

/// Nearest-neighbour resampling of a source volume (`values` on `source`) onto a target grid
/// through both affines (world RAS mm); target voxels outside the source are 0.
std::vector<double> resample_nearest(const ImageGrid& source, const std::vector<double>& values,
                                     const ImageGrid& target);
std::vector<double> resample_nearest(const NiftiVolume& source, const ImageGrid& target);

/// Exact Euclidean distance (mm) from every voxel to the nearest voxel of the mask (0 inside).
std::vector<float> distance_to(const Mask& mask, const ImageGrid& grid);

/// 6-connected components of a mask, numbered 1, 2, ... in scan order (deterministic).
std::vector<std::int32_t> connected_components(const Mask& mask, const ImageGrid& grid, std::int32_t* count);

/// The mask with its holes filled: voxels not reachable from the volume's border through
/// voxels outside the mask.
Mask fill_holes(const Mask& mask, const ImageGrid& grid);

/// The mask with its holes filled in every axial (k) slice (see the definition).
Mask fill_holes_axial(const Mask& mask, const ImageGrid& grid);

/// The largest 6-connected component of a mask (the first in scan order on a tie).
Mask largest_component(const Mask& mask, const ImageGrid& grid);

/// Otsu's threshold of a 256-bin histogram; values at or below it form the lower class.
int otsu_threshold(const std::array<std::int64_t, 256>& histogram);

/// The two thresholds of a deterministic three-class k-means of a 256-bin histogram.
std::array<double, 2> three_class_thresholds(const std::array<std::int64_t, 256>& histogram);

/// One pass of a 3x3x3 majority filter over the classes 1..3 inside the mask.
std::vector<std::int8_t> majority_filter(const std::vector<std::int8_t>& cls, const Mask& mask,
                                         const ImageGrid& grid);

/// The mask eroded (erode) or dilated by one voxel through its six faces.
Mask step_mask(const Mask& mask, const ImageGrid& grid, bool erode);

} // namespace voxel_masks
} // namespace phantasm
