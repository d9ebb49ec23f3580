#include "anatomy/shape_build.hpp"

#include <stdexcept>

namespace phantasm {

// The members, one per file of anatomy/shape_builds/.
const ShapeBuild& ellipsoid_shape_build();
const ShapeBuild& superquadric_shape_build();
const ShapeBuild& box_shape_build();
const ShapeBuild& sheet_shape_build();
const ShapeBuild& mesh_shape_build();
const ShapeBuild& label_volume_shape_build();

const std::vector<const ShapeBuild*>& shape_builds() {
  // The registrations, beside those of shape_sources() (docs/architecture.md, Adding a variant).
  static const std::vector<const ShapeBuild*> builds{&ellipsoid_shape_build(), &superquadric_shape_build(),
                                                     &box_shape_build(),       &sheet_shape_build(),
                                                     &mesh_shape_build(),      &label_volume_shape_build()};
  return builds;
}

const ShapeBuild& shape_build(ShapeKind kind) {
  for (const ShapeBuild* build : shape_builds())
    if (build->kind == kind) return *build;
  throw std::logic_error("a shape kind without a member of the shape build registry");
}

} // namespace phantasm
