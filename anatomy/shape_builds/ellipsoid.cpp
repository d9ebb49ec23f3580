// An ellipsoid's organs: its implicit ellipsoid, fitted from its semi-axes.
#include "anatomy/shape_build.hpp"

namespace phantasm {

const ShapeBuild& ellipsoid_shape_build() {
  static const ShapeBuild build{
      ShapeKind::ellipsoid,
      [](const ShapeSettings& shape, const ShapeData*, const std::string&) {
        return make_ellipsoid(shape.center_mm, shape.radii_mm, rotation_from_degrees(shape.rotation_deg));
      },
      nullptr, [](const ShapeSettings& shape) -> Eigen::Vector3d { return shape.radii_mm; }};
  return build;
}

} // namespace phantasm
