// An ellipsoid: centre, semi-axes and rotation; its bounds are its extent.
#include "anatomy/shape_sources/shape_math.hpp"

namespace phantasm {

const ShapeSource& ellipsoid_shape_source() {
  using namespace shape_math;
  static const ShapeSource source = [] {
    ShapeSource s{ShapeKind::ellipsoid,
                  "ellipsoid",
                  "an ellipsoid: center_mm, radii_mm (semi-axes), rotation_deg",
                  {center(), radii(), rotation()}};
    s.nesting = NestingCheck::by_bounds;
    s.plan_tet_size = true;
    s.bounds = [](const ShapeSettings& shape) {
      // The support function of an ellipsoid R diag(r) S^2 along axis e is |diag(r) R^T e|.
      const Eigen::Matrix3d rotation = rotation_matrix(shape.rotation_deg);
      Eigen::Vector3d half_extent;
      for (int a = 0; a < 3; ++a)
        half_extent[a] = (shape.radii_mm.asDiagonal() * rotation.row(a).transpose()).norm();
      return WorldBox{shape.center_mm - half_extent, shape.center_mm + half_extent};
    };
    s.area_volume = [](const ShapeSettings& shape) {
      return std::pair{ellipsoid_area_mm2(shape.radii_mm), 4.0 / 3.0 * M_PI * shape.radii_mm.prod()};
    };
    return s;
  }();
  return source;
}

} // namespace phantasm
