#pragma once

#include "anatomy/organ.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "scene/scene.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelized_phantom.hpp"

namespace phantasm {

/// Voxelizes the reference phantom (and the deformed one with the motion fields when given) on
/// the scene's grid: each closed organ in the field of view becomes a level set of its patch
/// surface tessellated within voxelization.tessellation_tolerance_mm, at the grid's smallest
/// voxel size; open sheets (zero thickness) fill no voxel. What was done goes into `report`.
VoxelizedPhantom voxelize_phantom(const Scene& scene, const Phantom& reference, const Phantom* deformed,
                                  const PhantomDeformation* deformation, StageReport& report,
                                  Reporter& reporter);

} // namespace phantasm
