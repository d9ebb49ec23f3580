// Learn2Reg, LUMIR and voxelmorph: a 4-D (X, Y, Z, 3) NIfTI, u in voxels of the fixed grid along
// i, j, k, whatever its header says (the challenge's files carry an identity or none).
#include "evaluation/field_conventions.hpp"

namespace phantasm {

const FieldConventionType& learn2reg_field_convention() {
  static const FieldConventionType type = [] {
    FieldConventionType t{FieldConvention::learn2reg, "learn2reg",
                          "4-D (X, Y, Z, 3) NIfTI, u in voxels along i, j, k (Learn2Reg, LUMIR, voxelmorph)"};
    t.world_frame = false;
    t.stored = [](const FieldFrame& frame, const Eigen::Vector3d&, const Eigen::Vector3d& ras) {
      return Eigen::Vector3d(frame.index_from_ras * ras);
    };
    t.displacement = [](const FieldFrame& frame, const Eigen::Vector3d&, const Eigen::Vector3d& voxels) {
      return Eigen::Vector3d(frame.ras_from_index * voxels);
    };
    t.confusions = {{FieldConvention::mrtrix_displacement, "voxels read as mm (and axes as RAS)"}};
    return t;
  }();
  return type;
}

} // namespace phantasm
