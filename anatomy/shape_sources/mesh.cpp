// A closed triangle mesh read from a file: its extent is known once read, so its nesting is
// checked when its organ is built.
#include "anatomy/shape_source.hpp"

namespace phantasm {

const ShapeSource& mesh_shape_source() {
  static const ShapeSource source = [] {
    ShapeParameter file{"file", ShapeParameter::Kind::file};
    file.required = true;
    file.extensions = {".stl", ".obj", ".ply", ".vtp"};
    ShapeSource s{ShapeKind::mesh, "mesh", "a closed triangle mesh: file (.stl, .obj, .ply or .vtp)", {file}};
    s.nesting = NestingCheck::when_built;
    s.input = ShapeInput::triangle_mesh;
    return s;
  }();
  return source;
}

} // namespace phantasm
