// A sheet's organs: a structured triangle sheet, with no target (no volume to fit or voxelize).
#include "anatomy/shape_build.hpp"
#include "anatomy/structured_mesh.hpp"

namespace phantasm {

const ShapeBuild& sheet_shape_build() {
  static const ShapeBuild build{ShapeKind::sheet,
                                [](const ShapeSettings&, const ShapeData*,
                                   const std::string&) -> std::unique_ptr<ImplicitShape> { return nullptr; },
                                [](Organ& organ, const OrganSettings&, const ShapeSettings& shape) {
                                  organ.sheet = structured_sheet(
                                      shape.size_mm.head<2>(), shape.cells.head<2>(),
                                      rotation_from_degrees(shape.rotation_deg), shape.center_mm);
                                }};
  return build;
}

} // namespace phantasm
