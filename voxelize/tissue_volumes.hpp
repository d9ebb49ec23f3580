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

/// The result of another state on the same grid, and the organs it came from: where every organ
/// takes the same values in both states (the organs that did not move, and the moved ones away
/// from their surfaces in both states), the voxels are copied from it instead of sampled again.
struct TissuesToReuse {
  const TissueVolumes* volumes = nullptr;
  const std::vector<VoxelizedOrgan>* organs = nullptr;
};

/// Each voxel's fraction of every tissue, held as TissueVolumes holds them (each label's tissue,
/// and the fractions of the voxels that are not whole): voxels whose centre is farther than half
/// a voxel diagonal from every surface belong whole to the deepest organ holding the centre; the others
/// are sampled at supersampling^3 points (the deepest organ holding each sample counts it).
/// The grid is taken in blocks of 8^3 voxels: an organ whose level set stores nothing near a
/// block (LevelSet::block_reach_mm) has one value over all of it, read once, so each organ is
/// probed only in the blocks its band reaches. There it is read at all the block's voxel centres
/// at once, and at a voxel's samples at once, as lattices (LevelSet::Probe::lattice) where the
/// grid's axes are the world's, point by point elsewhere. The values, hence the result, are the
/// same as probing every organ at every point. Parallel over slabs of blocks (OpenMP); the result
/// does not depend on the number of threads.
/// @param reuse another state's result: its voxels are copied in every block where each organ
///        (matched by label, depth and tissue) has the same level set or the same one value in
///        both, and the organs without a match (gaps) lie wholly outside; the same bytes as
///        sampling them again
TissueVolumes voxelize_tissues(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                               int tissue_count, int supersampling, const TissuesToReuse& reuse = {});

} // namespace phantasm
