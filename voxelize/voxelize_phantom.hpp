#pragma once

#include "anatomy/phantom.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/tissue_volumes.hpp"

#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// The volumes of one run: labels and fractions of both states, and the motion between them.
struct VoxelizedPhantom {
  ImageGrid grid;
  std::vector<std::string> tissues; ///< tissue names, in order of first use by an organ
  TissueVolumes reference;
  std::optional<TissueVolumes> deformed; ///< when the scene deforms
  std::optional<MotionFields> motion;    ///< when the scene deforms
  std::vector<Landmark> landmarks;       ///< both states (equal when nothing deforms)
  /// The organs' level sets by organ name, kept when the scene asks for .vdb output.
  std::vector<std::pair<std::string, LevelSet>> reference_level_sets, deformed_level_sets;
};

/// Voxelizes the reference phantom (and the deformed one with the motion fields when given) on
/// the scene's grid: each closed organ in the field of view becomes a level set of its patch
/// surface tessellated within voxelization.tessellation_tolerance_mm, at the grid's smallest
/// voxel size; open sheets (zero thickness) fill no voxel. What was done goes into `report`.
VoxelizedPhantom voxelize_phantom(const Scene& scene, const Phantom& reference, const Phantom* deformed,
                                  const PhantomDeformation* deformation, StageReport& report,
                                  Reporter& reporter);

} // namespace phantasm
