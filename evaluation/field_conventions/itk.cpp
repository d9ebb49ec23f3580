// ITK, elastix/transformix and ANTs: a 5-D (X, Y, Z, 1, 3) NIfTI, u in LPS mm.
#include "evaluation/field_conventions.hpp"
#include "geometry/ras_lps.hpp"

namespace phantasm {

const FieldConventionType& itk_field_convention() {
  static const FieldConventionType type = [] {
    FieldConventionType t{FieldConvention::itk, "itk",
                          "5-D (X, Y, Z, 1, 3) NIfTI, u in LPS mm (ITK, elastix/transformix, ANTs)"};
    t.components_in_fourth_dimension = false;
    t.stored = [](const FieldFrame&, const Eigen::Vector3d&, const Eigen::Vector3d& ras) {
      return lps_from_ras(ras);
    };
    t.displacement = [](const FieldFrame&, const Eigen::Vector3d&, const Eigen::Vector3d& lps) {
      return ras_from_lps(lps);
    };
    // No confusion: its 5-D layout is refused by the 4-D conventions' readers, and theirs by its.
    return t;
  }();
  return type;
}

} // namespace phantasm
