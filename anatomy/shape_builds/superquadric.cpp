// A superquadric's organs: its implicit superquadric, fitted from its semi-axes.
#include "anatomy/shape_build.hpp"

namespace phantasm {

const ShapeBuild& superquadric_shape_build() {
  static const ShapeBuild build{
      ShapeKind::superquadric,
      [](const ShapeSettings& shape, const ShapeData*, const std::string&) {
        return make_superquadric(shape.center_mm, shape.radii_mm, shape.exponent_1, shape.exponent_2,
                                 rotation_from_degrees(shape.rotation_deg));
      },
      nullptr, [](const ShapeSettings& shape) -> Eigen::Vector3d { return shape.radii_mm; }};
  return build;
}

} // namespace phantasm
