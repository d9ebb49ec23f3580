// The voxelization stage (voxelize_phantom): level sets of the organs' patch surfaces, tissue
// labels and fractions on the scene's grid, and motion fields when the phantom was deformed.
#pragma once

#include "anatomy/organ.hpp"
#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelize_settings.hpp"
#include "voxelize/voxelized_phantom.hpp"

namespace phantasm {

/// Voxelizes the reference phantom (and the deformed one with the motion fields when given) on
/// the grid: each closed organ in the field of view becomes a level set of its patch surface
/// (from the patches directly, or tessellated within settings.tessellation_tolerance_mm when
/// settings.level_sets_from_tessellation), at the grid's smallest voxel size;
/// where organs overlap the deepest in the organ table's nesting wins; open sheets (zero
/// thickness) fill no voxel. In the deformed state the space a moved organ leaves in a container
/// that stays is filled with settings.gap_fill under its own label (voxelize/gap_fill.hpp). What
/// was done goes into `report`.
/// @param settings sampling, tolerance, the organs' nominal bounds, whether to keep level sets
/// @param organs the organ table, in the phantom's organ order
/// @param grid the imaging grid (RAS mm)
/// @param deformation how each organ moved (the gaps and motion fields need it), with `deformed`
/// @throws SettingError naming deformation.gap_tissue when settings.gap_fill is neither air nor a
///         tissue of the organs
VoxelizedPhantom voxelize_phantom(const VoxelizationSettings& settings, const OrganTable& organs,
                                  const ImageGrid& grid, const Phantom& reference, const Phantom* deformed,
                                  const PhantomDeformation* deformation, StageReport& report,
                                  Reporter& reporter);

} // namespace phantasm
