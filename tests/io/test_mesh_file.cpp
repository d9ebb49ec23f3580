#include "anatomy/structured_mesh.hpp"
#include "core/error.hpp"
#include "io/mesh_file.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace phantasm;
using phantasm::testing::fresh_folder;
using phantasm::testing::input_error_message;
using phantasm::testing::write_text_file;
namespace fs = std::filesystem;

namespace {

/// An ASCII STL of a mesh: every triangle repeats its corners, as STL does.
std::string ascii_stl(const TriangleMesh& mesh) {
  std::ostringstream text;
  text.precision(17);
  text << "solid test\n";
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    text << "facet normal 0 0 0\nouter loop\n";
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = mesh.vertex(mesh.faces(f, k));
      text << "vertex " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    text << "endloop\nendfacet\n";
  }
  text << "endsolid test\n";
  return text.str();
}

// A unit cube as six quads, counter-clockwise seen from outside.
const char* k_cube_obj = R"(# cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

} // namespace

TEST(MeshFile, VtpRoundTripKeepsVerticesFacesAndPointData) {
  const fs::path folder = fresh_folder("mesh-vtp");
  TriangleMesh sphere = unit_icosphere(2);
  sphere.vertices *= 10.0;
  std::vector<double> values(static_cast<std::size_t>(sphere.vertex_count()) * 3, 0.25);
  write_vtp(folder / "sphere.vtp", sphere, {PointArray{"displacement_mm", 3, values, "RAS", "mm"}});
  const TriangleMesh back = read_triangle_mesh(folder / "sphere.vtp");
  ASSERT_EQ(back.vertex_count(), sphere.vertex_count());
  ASSERT_EQ(back.face_count(), sphere.face_count());
  EXPECT_EQ(back.vertices, sphere.vertices); // doubles, bit for bit
  EXPECT_EQ(back.faces, sphere.faces);
  EXPECT_THROW(write_vtp(folder / "bad.vtp", sphere, {PointArray{"short", 3, {1.0}, "RAS", ""}}),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(folder / "bad.vtp"));
}

TEST(MeshFile, StlWithRepeatedCornersIsMergedIntoAClosedMesh) {
  const fs::path folder = fresh_folder("mesh-stl");
  const TriangleMesh sphere = unit_icosphere(2);
  write_text_file(folder / "sphere.stl", ascii_stl(sphere));
  const TriangleMesh back = read_triangle_mesh(folder / "sphere.stl");
  EXPECT_EQ(back.vertex_count(), sphere.vertex_count());
  EXPECT_EQ(back.face_count(), sphere.face_count());
  EXPECT_NO_THROW(check_closed_manifold(back, "sphere.stl"));
  EXPECT_NEAR(enclosed_volume(back), enclosed_volume(sphere), 1e-5); // STL stores floats
}

TEST(MeshFile, ObjQuadsAreSplitIntoOutwardTriangles) {
  const fs::path folder = fresh_folder("mesh-obj");
  write_text_file(folder / "cube.obj", k_cube_obj);
  const TriangleMesh cube = read_triangle_mesh(folder / "cube.obj");
  EXPECT_EQ(cube.vertex_count(), 8);
  EXPECT_EQ(cube.face_count(), 12);
  EXPECT_NO_THROW(check_closed_manifold(cube, "cube.obj"));
  EXPECT_NEAR(enclosed_volume(cube), 1.0, 1e-12);
}

TEST(MeshFile, AsciiPlyIsRead) {
  const fs::path folder = fresh_folder("mesh-ply");
  const TriangleMesh sphere = unit_icosphere(1);
  std::ostringstream ply;
  ply.precision(17);
  ply << "ply\nformat ascii 1.0\nelement vertex " << sphere.vertex_count()
      << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << sphere.face_count()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (Eigen::Index i = 0; i < sphere.vertex_count(); ++i)
    ply << sphere.vertices(i, 0) << ' ' << sphere.vertices(i, 1) << ' ' << sphere.vertices(i, 2) << '\n';
  for (Eigen::Index f = 0; f < sphere.face_count(); ++f)
    ply << "3 " << sphere.faces(f, 0) << ' ' << sphere.faces(f, 1) << ' ' << sphere.faces(f, 2) << '\n';
  write_text_file(folder / "sphere.ply", ply.str());
  const TriangleMesh back = read_triangle_mesh(folder / "sphere.ply");
  EXPECT_EQ(back.face_count(), 80);
  EXPECT_NEAR(enclosed_volume(back), enclosed_volume(sphere), 1e-6); // VTK's PLY reader keeps floats
}

TEST(MeshFile, UnreadableFilesGetMessagesNamingTheFile) {
  const fs::path folder = fresh_folder("mesh-bad");
  EXPECT_EQ(input_error_message([&] { read_triangle_mesh(folder / "none.stl"); }),
            (folder / "none.stl").string() +
                ": expected a triangle mesh (.stl, .obj, .ply or .vtp), found no such file");
  write_text_file(folder / "mesh.off", "OFF\n");
  EXPECT_NE(
      input_error_message([&] { read_triangle_mesh(folder / "mesh.off"); }).find("found extension '.off'"),
      std::string::npos);
  write_text_file(folder / "empty.obj", "");
  EXPECT_NE(
      input_error_message([&] { read_triangle_mesh(folder / "empty.obj"); }).find("found an empty file"),
      std::string::npos);
  write_text_file(folder / "points.obj", "v 0 0 0\nv 1 0 0\n");
  EXPECT_EQ(input_error_message([&] { read_triangle_mesh(folder / "points.obj"); }),
            (folder / "points.obj").string() + ": expected triangles, found none");
  write_text_file(folder / "garbage.vtp", "<VTKFile type='nonsense'>");
  EXPECT_NE(
      input_error_message([&] { read_triangle_mesh(folder / "garbage.vtp"); }).find("garbage.vtp: expected"),
      std::string::npos);
}

TEST(MeshFile, VtuRoundTripKeepsPositiveTetsAndBoundary) {
  const fs::path folder = fresh_folder("mesh-vtu");
  const TetMesh box = structured_box({20, 10, 30}, {2, 1, 3}, Eigen::Matrix3d::Identity(), {1, 2, 3});
  write_vtu(folder / "box.vtu", box);
  const TetMesh back = read_vtu(folder / "box.vtu");
  EXPECT_EQ(back.vertices, box.vertices);
  EXPECT_EQ(back.tets, box.tets);
  EXPECT_EQ(back.boundary_faces.rows(), box.boundary_faces.rows());
  for (Eigen::Index t = 0; t < back.tets.rows(); ++t)
    EXPECT_GT(tet_volume(back, t), 0.0);
  EXPECT_THROW(read_vtu(folder / "none.vtu"), InputError);
}

// Every mesh file states the frame and units of its points and point arrays in its field data
// (a tet mesh's displacement_mm is RAS like its points, unlike the LPS NIfTI fields), read back
// with VTK's Python module as ParaView or a script would; SPACE is the field 3D Slicer reads.
TEST(MeshFile, FieldDataStateTheFrameAndUnitsOfEveryArray) {
  const fs::path folder = fresh_folder("mesh-frames");
  const TetMesh box = structured_box({20, 10, 30}, {2, 1, 3}, Eigen::Matrix3d::Identity(), {1, 2, 3});
  std::vector<double> values(static_cast<std::size_t>(box.vertices.rows()) * 3, 0.5);
  write_vtu(folder / "box.vtu", box, {PointArray{"displacement_mm", 3, values, "RAS", "mm"}});
  write_vtp(folder / "sphere.vtp", unit_icosphere(1));
  write_text_file(folder / "check.py", R"(import sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
for name in sys.argv[1:]:
    reader = vtk.vtkXMLUnstructuredGridReader() if name.endswith(".vtu") else vtk.vtkXMLPolyDataReader()
    reader.SetFileName(name)
    reader.Update()
    data = reader.GetOutput().GetFieldData()
    values = {data.GetAbstractArray(i).GetName(): data.GetAbstractArray(i).GetValue(0)
              for i in range(data.GetNumberOfArrays())}
    print(name.rsplit("/", 1)[1], sorted((k, v) for k, v in values.items() if k != "conventions"))
    print("conventions" in values)
)");
  const phantasm::testing::CommandResult result =
      phantasm::testing::run_command({PHANTASM_PYTHON, (folder / "check.py").string(),
                                      (folder / "box.vtu").string(), (folder / "sphere.vtp").string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.out,
            "box.vtu [('Points_frame', 'RAS'), ('Points_units', 'mm'), ('SPACE', 'RAS'), "
            "('displacement_mm_frame', 'RAS'), ('displacement_mm_units', 'mm')]\nTrue\n"
            "sphere.vtp [('Points_frame', 'RAS'), ('Points_units', 'mm'), ('SPACE', 'RAS')]\nTrue\n");
}
