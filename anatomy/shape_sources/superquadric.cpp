// A superquadric: an ellipsoid's keys and two exponents that make it boxier (below 1) or
// pinched (above 1); its bounds, the box of its radii, may be larger than its extent.
#include "anatomy/shape_sources/shape_math.hpp"

#include <algorithm>

namespace phantasm {

const ShapeSource& superquadric_shape_source() {
  using namespace shape_math;
  static const ShapeSource source = [] {
    std::vector<ShapeParameter> parameters{center(), radii(), rotation()};
    // Exponents below 0.1 or above 4 make creases sharper than a patch mesh can follow.
    for (const auto& [key, member] : {std::pair{"exponent_1", &ShapeSettings::exponent_1},
                                      std::pair{"exponent_2", &ShapeSettings::exponent_2}}) {
      ShapeParameter p{key, ShapeParameter::Kind::number, nullptr, member, 0.1, 4.0};
      p.required = true;
      parameters.push_back(p);
    }
    ShapeSource s{ShapeKind::superquadric, "superquadric",
                  "a superquadric: an ellipsoid's keys and exponent_1, exponent_2 (1: ellipsoid)",
                  parameters};
    s.bounds = [](const ShapeSettings& shape) { return rotated_box_bounds(shape, shape.radii_mm); };
    s.area_volume = [](const ShapeSettings& shape) {
      // Exponents below 1 make it boxier (up to the bounding box, 6/pi of the ellipsoid's volume).
      const double boxy = std::clamp(2.0 - 0.5 * (shape.exponent_1 + shape.exponent_2), 0.5, 1.5);
      const double factor = 1.0 + (6.0 / M_PI - 1.0) * std::clamp(boxy - 1.0, 0.0, 1.0);
      return std::pair{factor * ellipsoid_area_mm2(shape.radii_mm),
                       factor * 4.0 / 3.0 * M_PI * shape.radii_mm.prod()};
    };
    return s;
  }();
  return source;
}

} // namespace phantasm
