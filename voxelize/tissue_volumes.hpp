#pragma once

#include "core/grid.hpp"
#include "voxelize/level_set.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace phantasm {

/// One organ as the voxelizer sees it.
struct VoxelizedOrgan {
  const LevelSet* level_set = nullptr;
  int depth = 0;  ///< nesting depth: a point inside several organs belongs to the deepest
  int label = 0;  ///< dseg index (1..)
  int tissue = 0; ///< index into the tissue list
};

/// Labels and partial-volume fractions on an image grid.
struct TissueVolumes {
  std::vector<std::int32_t>
      labels; ///< voxel_count(): the organ (dseg index) of the largest fraction, 0 background
  std::vector<std::vector<float>> fractions; ///< per tissue, voxel_count(); with background they sum to 1
  std::vector<float> background;             ///< voxel_count()
  std::size_t supersampled_voxels = 0;       ///< voxels near a surface, where samples were taken
};

/// Each voxel's fraction of every tissue: voxels whose centre is farther than half a voxel
/// diagonal from every surface belong whole to the deepest organ holding the centre; the others
/// are sampled at supersampling^3 points (the deepest organ holding each sample counts it).
/// Parallel over slices (OpenMP); the result does not depend on the number of threads.
TissueVolumes voxelize_tissues(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                               int tissue_count, int supersampling);

} // namespace phantasm
