// A box's organs: a structured tet mesh of its cells, whose boundary is the patch base mesh with
// flat faces (a box needs no bumps).
#include "anatomy/patch_fit.hpp"
#include "anatomy/shape_build.hpp"
#include "anatomy/structured_mesh.hpp"
#include "anatomy/tet_mesh.hpp"

namespace phantasm {

const ShapeBuild& box_shape_build() {
  static const ShapeBuild build{
      ShapeKind::box,
      [](const ShapeSettings& shape, const ShapeData*, const std::string&) {
        return make_box(shape.center_mm, shape.size_mm, rotation_from_degrees(shape.rotation_deg));
      },
      [](Organ& organ, const OrganSettings& settings, const ShapeSettings& shape) {
        TetMesh tets = structured_box(shape.size_mm, shape.cells, rotation_from_degrees(shape.rotation_deg),
                                      shape.center_mm);
        TriangleMesh base = boundary_surface(tets, &organ.tet_vertex_of_surface_vertex);
        organ.surface.emplace(base, "organ " + settings.name);
        if (settings.solid) organ.solid = std::move(tets);
        organ.fit = measure_source_fit(*organ.surface, *organ.target);
      }};
  return build;
}

} // namespace phantasm
