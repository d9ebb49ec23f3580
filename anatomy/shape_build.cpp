#include "anatomy/shape_build.hpp"

#include "core/registry.hpp"

namespace phantasm {

// The members, one per file of anatomy/shape_builds/.
const ShapeBuild& ellipsoid_shape_build();
const ShapeBuild& superquadric_shape_build();
const ShapeBuild& box_shape_build();
const ShapeBuild& sheet_shape_build();
const ShapeBuild& mesh_shape_build();
const ShapeBuild& label_volume_shape_build();

namespace {

const Registry<ShapeBuild, ShapeKind>& shape_build_registry() {
  // The registrations, beside those of shape_sources() (docs/architecture.md, Adding a variant).
  static const Registry<ShapeBuild, ShapeKind> builds("shape build", &ShapeBuild::kind,
                                                      {&ellipsoid_shape_build(), &superquadric_shape_build(),
                                                       &box_shape_build(), &sheet_shape_build(),
                                                       &mesh_shape_build(), &label_volume_shape_build()});
  return builds;
}

} // namespace

const std::vector<const ShapeBuild*>& shape_builds() {
  return shape_build_registry().members();
}

const ShapeBuild& shape_build(ShapeKind kind) {
  return shape_build_registry().at(kind);
}

} // namespace phantasm
