// A box meshed as a structured grid of hexahedral cells, five tets each: its surface is made of
// the cells' faces (no fitted bumps), its bounds are its extent.
#include "anatomy/shape_sources/shape_math.hpp"

namespace phantasm {

const ShapeSource& box_shape_source() {
  using namespace shape_math;
  static const ShapeSource source = [] {
    ShapeSource s{ShapeKind::box,
                  "box",
                  "a box of structured hexahedral cells: center_mm, size_mm, cells, rotation_deg",
                  {center(), rotation(), lengths("size_mm", &ShapeSettings::size_mm), cells(3)}};
    s.nesting = NestingCheck::by_bounds;
    s.bounds = [](const ShapeSettings& shape) { return rotated_box_bounds(shape, 0.5 * shape.size_mm); };
    s.area_volume = [](const ShapeSettings& shape) {
      const Eigen::Vector3d e = shape.size_mm;
      return std::pair{2.0 * (e.x() * e.y() + e.y() * e.z() + e.x() * e.z()), e.prod()};
    };
    s.structured = [](const ShapeSettings& shape, bool solid) {
      // Five tets per cell, its boundary quads split in two.
      const Eigen::Vector3d c = shape.cells.cast<double>();
      StructuredCounts counts;
      counts.patches = 4.0 * (c.x() * c.y() + c.y() * c.z() + c.x() * c.z());
      if (solid) {
        counts.tets = 5.0 * c.prod();
        counts.tet_size_mm = (shape.size_mm.array() / c.array()).maxCoeff();
      }
      return counts;
    };
    return s;
  }();
  return source;
}

} // namespace phantasm
