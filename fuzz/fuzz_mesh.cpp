// libFuzzer target: the mesh files a scene's organs are read from (docs/scene-format.md, shape
// `mesh`: .stl, .obj, .ply, .vtp) as the run reads them: read_shape_files (VTK's readers, the
// triangle and coordinate checks), then the closed-manifold check and the enclosed volume the
// anatomy stage starts with. The input's first byte chooses the format (byte % 4: stl, obj, ply,
// vtp); the rest is the file. Only InputError may refuse a file.
#include "fuzz/fuzz_support.hpp"
#include "geometry/triangle_mesh.hpp"
#include "io/shape_files.hpp"

#include <cstdint>
#include <string>

using namespace phantasm;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const extensions[] = {".stl", ".obj", ".ply", ".vtp"};
  const std::filesystem::path path =
      fuzz::write_scratch_file(std::string("organ") + extensions[data[0] % 4], data + 1, size - 1);
  fuzz::expect_input_errors_only("read_shape_files", [&] {
    AnatomySettings anatomy;
    OrganSettings organ;
    organ.name = "organ";
    organ.shape.kind = ShapeKind::mesh;
    organ.shape.file = path;
    anatomy.organs.push_back(organ);
    const auto files = read_shape_files(anatomy);
    const TriangleMesh& mesh = *files.at("organ").mesh;
    for (Eigen::Index i = 0; i < mesh.faces.size(); ++i)
      if (mesh.faces.data()[i] < 0 || mesh.faces.data()[i] >= mesh.vertex_count())
        fuzz::finding("a face refers to vertex " + std::to_string(mesh.faces.data()[i]) + " of " +
                      std::to_string(mesh.vertex_count()));
    check_closed_manifold(mesh, path.string());
    (void)enclosed_volume(mesh);
  });
  return 0;
}
