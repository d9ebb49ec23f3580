// The settings the voxelization stage reads, and what it needs of other sections (outputs,
// deformation, organ bounds), filled by the scene parser; Eigen and the standard library only.
#pragma once

#include "anatomy/anatomy_settings.hpp"

#include <optional>
#include <vector>

namespace phantasm {

struct VoxelizationSettings {
  int supersampling = 4;                  ///< samples per voxel edge for partial-volume fractions
  double tessellation_tolerance_mm = 0.2; ///< patch surface tessellation deviation

  // Set by the scene from other sections.
  bool deformed = false;           ///< deformation.mode is not none: a deformed state is made
  bool keep_level_sets = false;    ///< outputs.vdb: the organs' level sets are kept for .vdb files
  bool labels = true;              ///< outputs.labels
  bool fractions = true;           ///< outputs.fractions or outputs.images (images need them)
  bool displacement_fields = true; ///< outputs.displacement_fields
  bool jacobian = true;            ///< outputs.jacobian
  bool landmarks = true;           ///< outputs.landmarks
  /// Per organ in scene order: the bounds of its shape as written (before seeded variation),
  /// none for shapes known only from their file (analytic_shape_bounds()).
  std::vector<std::optional<WorldBox>> organ_bounds_mm;
};

} // namespace phantasm
