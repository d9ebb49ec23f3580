// The voxelization stage (voxelize_phantom): level sets of the organs' patch surfaces, tissue
// labels and fractions on the scene's grid, and motion fields when the phantom was deformed.
#pragma once

#include "anatomy/organ.hpp"
#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/voxelize_settings.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <memory>
#include <optional>
#include <vector>

namespace phantasm {

/// Each organ's patch height bounds (patch_height_ranges), by organ index of the phantom; none
/// where not computed. Found by the state that builds an organ's level set first and reused by
/// the other: the bumps do not change when the base moves.
using OrganHeightRanges = std::vector<std::optional<std::vector<HeightRange>>>;

/// The voxelized reference state: the same for every run with the same reference phantom, grid,
/// organ table and the settings that shape it, whatever the deformation (pipeline/reference_cache.hpp
/// keeps it across runs).
struct ReferenceVoxelization {
  /// the phantom's organ index of each level set (the closed organs in the field of view), ascending
  std::vector<int> organs;
  std::vector<std::shared_ptr<const LevelSet>> level_sets;
  OrganHeightRanges height_ranges; ///< the deformed state's level sets reuse them
  TissueVolumes volumes;           ///< labels and fractions
  /// The organs' deepest-point candidates from these labels (voxelize/landmarks.hpp): each
  /// deformation's landmarks pick from them. None: the landmarks read the labels themselves.
  std::optional<DeepestCandidates> deepest_candidates;
};

/// The reference state alone, as voxelize_phantom builds it: what a voxelize_phantom given it
/// (reference_state) takes instead of building it, for the same result bit for bit. It needs the
/// reference phantom only, so it can be built while the deformation is solved. Reports nothing
/// (voxelize_phantom reports the state it is given as one it built); polls for cancellation.
ReferenceVoxelization voxelize_reference_state(const VoxelizationSettings& settings, const OrganTable& organs,
                                               const ImageGrid& grid, const Phantom& reference);

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
/// @param reference_state holding a state: the reference state is that one (its volumes are
///        moved into the result) instead of being built; it must be what this call builds (the
///        same reference phantom, grid, organ table and settings), and the result is then the
///        same, bit for bit. Empty: receives the reference state this call built, all but its
///        volumes, which are the result's `reference`. Null: built and not given back.
/// @throws SettingError naming deformation.gap_tissue when settings.gap_fill is neither air nor a
///         tissue of the organs
VoxelizedPhantom voxelize_phantom(const VoxelizationSettings& settings, const OrganTable& organs,
                                  const ImageGrid& grid, const Phantom& reference, const Phantom* deformed,
                                  const PhantomDeformation* deformation, StageReport& report,
                                  Reporter& reporter,
                                  std::optional<ReferenceVoxelization>* reference_state = nullptr);

} // namespace phantasm
