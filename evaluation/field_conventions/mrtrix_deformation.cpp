// MRtrix3's deformation field (mrtransform -warp): a 4-D (X, Y, Z, 3) NIfTI, the position x + u in
// scanner RAS mm.
#include "evaluation/field_conventions.hpp"

namespace phantasm {

const FieldConventionType& mrtrix_deformation_field_convention() {
  static const FieldConventionType type = [] {
    FieldConventionType t{FieldConvention::mrtrix_deformation, "mrtrix-deformation",
                          "4-D (X, Y, Z, 3) NIfTI, x + u in scanner RAS mm (MRtrix3 mrtransform -warp)"};
    t.stored = [](const FieldFrame& frame, const Eigen::Vector3d& ijk, const Eigen::Vector3d& ras) {
      return Eigen::Vector3d(frame.grid.world_from_index(ijk) + ras);
    };
    t.displacement = [](const FieldFrame& frame, const Eigen::Vector3d& ijk,
                        const Eigen::Vector3d& position) {
      return Eigen::Vector3d(position - frame.grid.world_from_index(ijk));
    };
    t.confusions = {{FieldConvention::mrtrix_displacement, "positions read as displacements"}};
    return t;
  }();
  return type;
}

} // namespace phantasm
