// MRtrix3's displacement field (warpconvert ... displacement) and dipy's: a 4-D (X, Y, Z, 3)
// NIfTI, u in scanner RAS mm.
#include "evaluation/field_conventions.hpp"

namespace phantasm {

const FieldConventionType& mrtrix_displacement_field_convention() {
  static const FieldConventionType type = [] {
    FieldConventionType t{
        FieldConvention::mrtrix_displacement, "mrtrix-displacement",
        "4-D (X, Y, Z, 3) NIfTI, u in scanner RAS mm (MRtrix3 warpconvert displacement, dipy)"};
    t.stored = [](const FieldFrame&, const Eigen::Vector3d&, const Eigen::Vector3d& ras) { return ras; };
    t.displacement = [](const FieldFrame&, const Eigen::Vector3d&, const Eigen::Vector3d& ras) {
      return ras;
    };
    t.confusions = {{FieldConvention::mrtrix_deformation, "displacements read as positions"},
                    {FieldConvention::learn2reg, "mm read as voxels (and RAS axes as i, j, k)"}};
    return t;
  }();
  return type;
}

} // namespace phantasm
