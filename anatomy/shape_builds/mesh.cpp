// A mesh's organs: minus the signed distance to its triangles, as read from its file.
#include "anatomy/phantom.hpp"
#include "anatomy/shape_build.hpp"
#include "core/error.hpp"

namespace phantasm {

const ShapeBuild& mesh_shape_build() {
  static const ShapeBuild build{
      ShapeKind::mesh, [](const ShapeSettings& shape, const ShapeData* file, const std::string& organ) {
        if (file == nullptr || !file->mesh)
          throw InputError("organ " + organ + ": its mesh file was not loaded");
        return make_mesh_shape(*file->mesh, "organ " + organ + " (" + shape.file.string() + ")");
      }};
  return build;
}

} // namespace phantasm
