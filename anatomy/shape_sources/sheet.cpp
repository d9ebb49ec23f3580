// A flat sheet of structured triangles in the shape's x-y plane: an open surface without
// interior (its organ is `solid: false`, simulated as a shell).
#include "anatomy/shape_sources/shape_math.hpp"

namespace phantasm {

const ShapeSource& sheet_shape_source() {
  using namespace shape_math;
  static const ShapeSource source = [] {
    ShapeSource s{
        ShapeKind::sheet,
        "sheet",
        "a flat sheet of structured triangles (solid: false): center_mm, size_mm [x, y], cells [x, y], "
        "rotation_deg",
        {center(), rotation(), lengths("size_mm", &ShapeSettings::size_mm, ShapeParameter::Kind::extent2),
         cells(2)}};
    s.has_interior = false;
    s.bounds = [](const ShapeSettings& shape) { return rotated_box_bounds(shape, 0.5 * shape.size_mm); };
    s.area_volume = [](const ShapeSettings& shape) {
      return std::pair{shape.size_mm.x() * shape.size_mm.y(), 0.0};
    };
    s.structured = [](const ShapeSettings& shape, bool) {
      StructuredCounts counts;
      counts.patches = 2.0 * shape.cells.x() * shape.cells.y();
      return counts;
    };
    return s;
  }();
  return source;
}

} // namespace phantasm
