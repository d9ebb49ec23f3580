// Tissue labels and fractions of every voxel from the organs' level sets and nesting: whole
// voxels far from surfaces, supersampled near them; independent of the thread count.
#pragma once

#include "core/grid.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <vector>

namespace phantasm {

/// One organ as the voxelizer sees it.
struct VoxelizedOrgan {
  const LevelSet* level_set = nullptr;
  int depth = 0; ///< a point inside several organs belongs to the deepest (organs: twice their nesting depth)
  int label = 0; ///< dseg index (1..)
  int tissue = 0; ///< index into the tissue list; -1: no tissue (a gap of air), counted as background
};

/// Each voxel's fraction of every tissue: voxels whose centre is farther than half a voxel
/// diagonal from every surface belong whole to the deepest organ holding the centre; the others
/// are sampled at supersampling^3 points (the deepest organ holding each sample counts it).
/// Parallel over slices (OpenMP); the result does not depend on the number of threads.
TissueVolumes voxelize_tissues(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                               int tissue_count, int supersampling);

} // namespace phantasm
