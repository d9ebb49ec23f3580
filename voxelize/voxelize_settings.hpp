// The settings the voxelization stage reads, and what it needs of other sections (outputs,
// deformation, organ bounds), filled by the scene parser; Eigen and the standard library only.
#pragma once

#include "anatomy/anatomy_settings.hpp"

#include <optional>
#include <string>
#include <vector>

namespace phantasm {

struct VoxelizationSettings {
  int supersampling = 4;                  ///< samples per voxel edge for partial-volume fractions
  double tessellation_tolerance_mm = 0.2; ///< patch surface tessellation deviation
  /// What fills the space a moved organ leaves inside a container that stays, as the scene wrote
  /// it (deformation.gap_tissue): "air" or the tissue of an organ; empty when not given.
  std::string gap_tissue;
  /// Level sets through tessellations within tessellation_tolerance_mm and OpenVDB's
  /// mesh-to-volume instead of from the patch surfaces directly (slower; kept to compare).
  bool level_sets_from_tessellation = false;

  // Set by the scene from other sections.
  bool deformed = false;           ///< deformation.mode is not none: a deformed state is made
  bool keep_level_sets = false;    ///< outputs.vdb: the organs' level sets are kept for .vdb files
  bool labels = true;              ///< outputs.labels
  bool fractions = true;           ///< outputs.fractions or outputs.images (images need them)
  bool displacement_fields = true; ///< outputs.displacement_fields
  bool jacobian = true;            ///< outputs.jacobian
  bool landmarks = true;           ///< outputs.landmarks
  int dense_landmarks = 0;         ///< per organ, outputs.dense_landmarks (0 without landmarks)
  /// The tissue of every gap (docs/volumes-and-images.md, "The gap"): gap_tissue, or when it is
  /// empty the scene's default (CSF when the container holds CSF, else air); "air" fills the gap
  /// with background (no signal).
  std::string gap_fill = "air";
  /// Per organ in scene order: the bounds of its shape as written (before seeded variation),
  /// none for shapes known only from their file (analytic_shape_bounds()).
  std::vector<std::optional<WorldBox>> organ_bounds_mm;
};

} // namespace phantasm
