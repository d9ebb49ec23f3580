#include "anatomy/structured_mesh.hpp"
#include "core/error.hpp"
#include "io/mesh_file.hpp"
#include "io/vtk_xml_file.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

using namespace phantasm;
using phantasm::testing::CommandResult;
using phantasm::testing::fresh_folder;
using phantasm::testing::input_error_message;
using phantasm::testing::read_file;
using phantasm::testing::run_command;
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

// The dataset is written on several threads at once, and the first VTK objects of a run may be
// made on all of them together. VTK makes its object factories' registry on first use without a
// lock: two threads each made one and one leaked (the sanitizer build's leak check, which runs at
// a process's exit, failed about one run in five). This test runs itself again in 20 processes;
// in each, the first VTK objects are made by 16 threads released together. Every file must be
// whole and every process must end well (in the sanitizer build, with no leak).
TEST(MeshFile, FirstMeshesOfAProcessWrittenOnManyThreadsAtOnce) {
  const TriangleMesh sphere = unit_icosphere(1);
  if (const char* child_folder = std::getenv("PHANTASM_TEST_FIRST_VTK_FOLDER")) {
    constexpr int k_threads = 16;
    std::atomic<int> waiting{k_threads};
    std::vector<std::thread> threads;
    for (int t = 0; t < k_threads; ++t)
      threads.emplace_back([&, t] {
        waiting.fetch_sub(1);
        while (waiting.load() > 0)
          std::this_thread::yield();
        write_vtp(fs::path(child_folder) / (std::to_string(t) + ".vtp"), sphere, {});
      });
    for (std::thread& thread : threads)
      thread.join();
    return;
  }
  const fs::path folder = fresh_folder("mesh-threads");
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  for (int c = 0; c < 20; ++c) {
    const fs::path child = folder / std::to_string(c);
    fs::create_directories(child);
    const CommandResult run =
        run_command({"/usr/bin/env", "PHANTASM_TEST_FIRST_VTK_FOLDER=" + child.string(), self,
                     "--gtest_filter=MeshFile.FirstMeshesOfAProcessWrittenOnManyThreadsAtOnce"});
    ASSERT_EQ(run.exit_code, 0) << "process " << c << ":\n" << run.out << run.err;
    for (int t = 0; t < 16; ++t) {
      const TriangleMesh back = read_triangle_mesh(child / (std::to_string(t) + ".vtp"));
      ASSERT_EQ(back.vertices, sphere.vertices) << c << "/" << t;
      ASSERT_EQ(back.faces, sphere.faces) << c << "/" << t;
    }
  }
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

// Cell arrays (a label per tet as Int32, a real per tet as Float64) are written with the mesh,
// read back by read_vtu_cells value for value, and leave read_vtu's mesh as it was; the file's
// bytes are the same each time it is written.
TEST(MeshFile, VtuCellArraysRoundTripAsInt32AndFloat64) {
  const fs::path folder = fresh_folder("mesh-vtu-cell-arrays");
  const TetMesh box = structured_box({20, 10, 30}, {2, 1, 3}, Eigen::Matrix3d::Identity(), {1, 2, 3});
  const auto tets = static_cast<std::size_t>(box.tets.rows());
  CellArray labels{"organ_label", {}, true, "", {{2, "grey_matter"}, {7, "white_matter"}}};
  CellArray ratios{"det_F", {}, false, "", {}};
  for (std::size_t t = 0; t < tets; ++t) {
    labels.values.push_back(t % 3 == 0 ? 7 : 2);
    ratios.values.push_back(1.0 + 1e-3 * static_cast<double>(t) + 1e-17);
  }
  std::vector<double> displacement(static_cast<std::size_t>(box.vertices.rows()) * 3, 0.5);
  const std::vector<PointArray> points{PointArray{"displacement_mm", 3, displacement, "RAS", "mm"}};
  write_vtu(folder / "box.vtu", box, points, {labels, ratios});
  const std::string bytes = read_file(folder / "box.vtu");
  write_vtu(folder / "box.vtu", box, points, {labels, ratios});
  EXPECT_EQ(read_file(folder / "box.vtu"), bytes);

  const VtuCells cells = read_vtu_cells(folder / "box.vtu", true);
  ASSERT_EQ(cells.cell_arrays.size(), 2u);
  EXPECT_EQ(cells.cell_arrays[0].name, "organ_label");
  EXPECT_EQ(cells.cell_arrays[0].components, 1);
  EXPECT_EQ(cells.cell_arrays[0].values, labels.values);
  EXPECT_EQ(cells.cell_arrays[1].name, "det_F");
  EXPECT_EQ(cells.cell_arrays[1].values, ratios.values);               // doubles, bit for bit
  EXPECT_TRUE(read_vtu_cells(folder / "box.vtu").cell_arrays.empty()); // only when asked for
  // Int32 on disk: the array's declaration in the XML header, before the appended data.
  EXPECT_NE(bytes.find("<DataArray type=\"Int32\" Name=\"organ_label\""), std::string::npos);
  EXPECT_NE(bytes.find("<DataArray type=\"Float64\" Name=\"det_F\""), std::string::npos);
  const TetMesh back = read_vtu(folder / "box.vtu");
  EXPECT_EQ(back.vertices, box.vertices);
  EXPECT_EQ(back.tets, box.tets);

  // Wrong lengths, and integers that are no whole Int32, are refused and write nothing.
  EXPECT_THROW(write_vtu(folder / "short.vtu", box, {}, {CellArray{"short", {1.0}, true, "", {}}}),
               std::invalid_argument);
  std::vector<double> halves(tets, 0.5);
  EXPECT_THROW(write_vtu(folder / "half.vtu", box, {}, {CellArray{"half", halves, true, "", {}}}),
               std::invalid_argument);
  std::vector<double> huge(tets, 3e9);
  EXPECT_THROW(write_vtu(folder / "huge.vtu", box, {}, {CellArray{"huge", huge, true, "", {}}}),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(folder / "short.vtu"));
  EXPECT_FALSE(fs::exists(folder / "half.vtu"));
  EXPECT_FALSE(fs::exists(folder / "huge.vtu"));

  // Pieces are concatenated; an array a piece lacks, and string arrays, are left out.
  const std::string piece =
      "<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
      "<CellData><DataArray type=\"Int16\" Name=\"label\" format=\"ascii\">LABEL</DataArray>EXTRA"
      "<DataArray type=\"String\" Name=\"note\" format=\"ascii\">104 105 0</DataArray></CellData>\n"
      "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
      "0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>\n"
      "<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>\n"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n"
      "</Piece>";
  const auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    return text.replace(text.find(from), from.size(), to);
  };
  const std::string first =
      replaced(replaced(piece, "LABEL", "-4"), "EXTRA",
               "<DataArray type=\"Float32\" Name=\"only_first\" format=\"ascii\">0.5</DataArray>");
  const std::string second = replaced(replaced(piece, "LABEL", "9"), "EXTRA", "");
  write_text_file(folder / "pieces.vtu",
                  "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                  "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>" +
                      first + second + "</UnstructuredGrid></VTKFile>\n");
  const VtuCells pieces = read_vtu_cells(folder / "pieces.vtu", true);
  ASSERT_EQ(pieces.cells.size(), 2u);
  ASSERT_EQ(pieces.cell_arrays.size(), 1u);
  EXPECT_EQ(pieces.cell_arrays[0].name, "label");
  EXPECT_EQ(pieces.cell_arrays[0].values, (std::vector<double>{-4, 9}));
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
  // A file with cell arrays also names the values of its labels, as two arrays of field data.
  const std::vector<double> labels(static_cast<std::size_t>(box.tets.rows()), 3.0);
  const std::vector<double> ratios(static_cast<std::size_t>(box.tets.rows()), 1.5);
  write_vtu(folder / "labelled.vtu", box, {},
            {CellArray{"organ_label", labels, true, "", {{3, "csf"}, {4, "grey_matter"}}},
             CellArray{"det_F", ratios, false, "", {}}});
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
    if name.endswith("labelled.vtu"):
        cells = reader.GetOutput().GetCellData()
        for i in range(cells.GetNumberOfArrays()):
            array = cells.GetArray(i)
            print(array.GetName(), array.GetDataTypeAsString(), array.GetNumberOfTuples(),
                  sorted(set(vtk_to_numpy(array).tolist())))
        for field in ("organ_label_values", "organ_label_names"):
            array = data.GetAbstractArray(field)
            print(field, [array.GetValue(i) for i in range(array.GetNumberOfValues())])
)");
  const phantasm::testing::CommandResult result = phantasm::testing::run_command(
      {PHANTASM_PYTHON, (folder / "check.py").string(), (folder / "box.vtu").string(),
       (folder / "sphere.vtp").string(), (folder / "labelled.vtu").string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.out,
            "box.vtu [('Points_frame', 'RAS'), ('Points_units', 'mm'), ('SPACE', 'RAS'), "
            "('displacement_mm_frame', 'RAS'), ('displacement_mm_units', 'mm')]\nTrue\n"
            "sphere.vtp [('Points_frame', 'RAS'), ('Points_units', 'mm'), ('SPACE', 'RAS')]\nTrue\n"
            "labelled.vtu [('Points_frame', 'RAS'), ('Points_units', 'mm'), ('SPACE', 'RAS'), "
            "('det_F_units', ''), ('organ_label_names', 'csf'), ('organ_label_units', ''), "
            "('organ_label_values', 3)]\nTrue\n"
            "organ_label int " +
                std::to_string(box.tets.rows()) + " [3]\ndet_F double " + std::to_string(box.tets.rows()) +
                " [1.5]\norgan_label_values [3, 4]\norgan_label_names ['csf', 'grey_matter']\n");
}

// Found by fuzz/fuzz_mesh.cpp: faces naming missing vertices (VTK's OBJ and PLY readers crashed on
// them), a binary STL whose count asks for more triangles than the file holds (VTK allocated
// them all first), and PLY headers that promise more than the file holds.
TEST(MeshFile, FacesAndCountsBeyondTheFileAreRefusedWithTheirPlace) {
  const fs::path folder = fresh_folder("mesh-hostile");
  write_text_file(folder / "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
  EXPECT_EQ(
      input_error_message([&] { read_triangle_mesh(folder / "far.obj"); }),
      (folder / "far.obj").string() +
          ": line 5: expected vertex indices that refer to the file's 3 vertices, found one of vertex 8 "
          "(counted from 0)");
  write_text_file(folder / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_NE(
      input_error_message([&] {
        read_triangle_mesh(folder / "zero.obj");
      }).find("line 4: expected vertex indices from 1 (or back from -1, the last vertex so far), found '0'"),
      std::string::npos);
  write_text_file(folder / "back.obj",
                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf -4 -2 -3\nf -4 -3 -1\nf -3 -2 -1\nf -4 -1 -2\n");
  EXPECT_EQ(read_triangle_mesh(folder / "back.obj").face_count(), 4);

  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  write_text_file(folder / "far.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  EXPECT_EQ(input_error_message([&] { read_triangle_mesh(folder / "far.ply"); }),
            (folder / "far.ply").string() + ": element face 0: expected vertex indices that refer to the "
                                            "file's 3 vertices, found one of vertex 7 "
                                            "(counted from 0)");
  write_text_file(folder / "short.ply", header + "0 0 0\n1 0 0\n");
  EXPECT_EQ(input_error_message([&] { read_triangle_mesh(folder / "short.ply"); }),
            (folder / "short.ply").string() +
                ": element vertex 2: expected a number, found the end of the file");
  write_text_file(folder / "huge.ply", "ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n");
  EXPECT_NE(input_error_message([&] {
              read_triangle_mesh(folder / "huge.ply");
            }).find("header line 3: expected 'element NAME COUNT' with a count the file can hold"),
            std::string::npos);

  // A binary PLY, big-endian, with an extra property and element read past.
  std::string binary =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
      "property double z\nproperty uchar flag\nelement face 4\nproperty list uchar int vertex_indices\n"
      "element note 1\nproperty short n\nend_header\n";
  const auto put = [&binary](const void* value, std::size_t size) {
    const auto* bytes = static_cast<const char*>(value);
    for (std::size_t b = size; b-- > 0;) // little-endian machine: reverse for big-endian
      binary += bytes[b];
  };
  const double corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& corner : corners) {
    for (const double x : corner)
      put(&x, 8);
    binary += '\1';
  }
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  for (const auto& face : faces) {
    binary += '\3';
    for (const int v : face)
      put(&v, 4);
  }
  binary += std::string("\0\7", 2);
  write_text_file(folder / "tet.ply", binary);
  const TriangleMesh tet = read_triangle_mesh(folder / "tet.ply");
  EXPECT_EQ(tet.vertex_count(), 4);
  EXPECT_EQ(tet.face_count(), 4);
  EXPECT_NO_THROW(check_closed_manifold(tet, "tet.ply"));
  EXPECT_NEAR(enclosed_volume(tet), 1.0 / 6.0, 1e-12);

  std::string stl(80, '\1'); // not text: read as binary
  const std::uint32_t count = 1000000000;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  stl.append(100, '\0');
  write_text_file(folder / "huge.stl", stl);
  EXPECT_EQ(
      input_error_message([&] { read_triangle_mesh(folder / "huge.stl"); }),
      (folder / "huge.stl").string() +
          ": expected a binary STL file of 84 + 50 bytes per triangle (50000000084 bytes for the 1000000000 "
          "triangles its header counts), found 184 bytes");
}

namespace {

/// Base64 as VTK writes it (RFC 4648, padded).
std::string base64(const std::vector<unsigned char>& bytes) {
  const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t chunk = std::uint32_t{bytes[i]} << 16 |
                                (i + 1 < bytes.size() ? std::uint32_t{bytes[i + 1]} << 8 : 0u) |
                                (i + 2 < bytes.size() ? std::uint32_t{bytes[i + 2]} : 0u);
    text += digits[chunk >> 18 & 63];
    text += digits[chunk >> 12 & 63];
    text += i + 1 < bytes.size() ? digits[chunk >> 6 & 63] : '=';
    text += i + 2 < bytes.size() ? digits[chunk & 63] : '=';
  }
  return text;
}

/// A compression header of UInt32 (little-endian) or UInt64 (big-endian) words.
std::vector<unsigned char> header_words(const std::vector<std::uint64_t>& words, bool uint64_big_endian) {
  std::vector<unsigned char> bytes;
  for (const std::uint64_t w : words) {
    if (uint64_big_endian) {
      for (int b = 7; b >= 0; --b)
        bytes.push_back(static_cast<unsigned char>(w >> (8 * b)));
    } else {
      for (int b = 0; b < 4; ++b)
        bytes.push_back(static_cast<unsigned char>(w >> (8 * b)));
    }
  }
  return bytes;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

} // namespace

// VTK's XML reader allocates what a file declares (points, cells, compressed block sizes) before
// it reads the data; a few bytes could ask for gigabytes. The fixtures were written by VTK 9.1:
// inline base64 with zlib and UInt32 headers, and appended base64 with LZMA, UInt64 big-endian
// headers; phantasm's own files are appended raw bytes with zlib.
TEST(MeshFile, VtkXmlSizesBeyondTheFileAreRefusedBeforeVtkAllocatesThem) {
  const fs::path data = fs::path(PHANTASM_SOURCE_DIR) / "tests/data/meshes";
  const fs::path inline_zlib = data / "tetrahedron-inline-zlib.vtp";
  const fs::path appended_lzma = data / "tetrahedron-appended-base64-lzma-bigendian.vtp";
  for (const fs::path& good : {inline_zlib, appended_lzma}) {
    const TriangleMesh mesh = read_triangle_mesh(good);
    EXPECT_EQ(mesh.vertex_count(), 4) << good;
    EXPECT_EQ(mesh.face_count(), 4) << good;
  }
  const fs::path folder = fresh_folder("mesh-vtk-sizes");
  const auto message = [&](const std::string& name, const std::string& text) {
    write_text_file(folder / name, text);
    return input_error_message([&] { read_triangle_mesh(folder / name); });
  };

  // Inline: the points' header (1 block of 32768 bytes, a last block of 48 bytes compressed into
  // 17) with blocks of nearly 4 GB, as a fuzzed file had.
  const std::string inline_text = read_file(inline_zlib);
  const std::string points_header = base64(header_words({1, 32768, 48, 17}, false));
  ASSERT_EQ(points_header, "AQAAAACAAAAwAAAAEQAAAA==");
  EXPECT_EQ(message("inline.vtp", replaced(inline_text, points_header,
                                           base64(header_words({1, 3978928655u, 3978928655u, 17}, false)))),
            (folder / "inline.vtp").string() +
                ": array 'Points': expected a compression header the file can hold, found block 0 of "
                "3978928655 bytes compressed into 17 (at most 8192 times as many bytes come out of a "
                "compressed one)");
  // Blocks of no bytes (VTK divided by zero), a last block larger than the others (VTK read past
  // its list of blocks), a last block among none (VTK's total size wrapped around).
  EXPECT_NE(
      message("zero.vtp", replaced(inline_text, points_header, base64(header_words({1, 0, 48, 17}, false))))
          .find("found blocks of 0 bytes and a last one of 48 (blocks of at least a byte, the last one "
                "no larger)"),
      std::string::npos);
  EXPECT_NE(
      message("last.vtp", replaced(inline_text, points_header, base64(header_words({1, 16, 48, 17}, false))))
          .find("found blocks of 16 bytes and a last one of 48"),
      std::string::npos);
  EXPECT_NE(
      message("none.vtp", replaced(inline_text, points_header, base64(header_words({0, 32768, 48}, false))))
          .find("found no blocks but a last one of 48 bytes"),
      std::string::npos);
  EXPECT_NE(
      message("points.vtp", replaced(inline_text, "NumberOfPoints=\"4\"", "NumberOfPoints=\"99999999999\""))
          .find("element Piece: expected NumberOfPoints the file can hold (at most "),
      std::string::npos);

  // Appended base64: the points' header with 2^40 blocks, then a block larger than the file.
  const std::string appended_text = read_file(appended_lzma);
  const std::string appended_header = base64(header_words({1, 32768, 48, 68}, true));
  ASSERT_EQ(appended_header, "AAAAAAAAAAEAAAAAAACAAAAAAAAAAAAwAAAAAAAAAEQ=");
  EXPECT_NE(message("blocks.vtp", replaced(appended_text, appended_header,
                                           base64(header_words({1ull << 40, 32768, 48, 68}, true))))
                .find("array 'Points': expected a compression header the file can hold, found 1099511627776 "
                      "blocks in a file of "),
            std::string::npos);
  EXPECT_NE(message("block.vtp", replaced(appended_text, appended_header,
                                          base64(header_words({1, 32768, 48, 1ull << 33}, true))))
                .find("found block 0 of 8589934592 compressed bytes, past the end of a file of "),
            std::string::npos);

  // Appended raw bytes (phantasm's own files): the first array's block sizes (full and partial
  // last), little-endian UInt64 words 1 and 2, set to 2^32.
  write_vtp(folder / "own.vtp", unit_icosphere(1));
  std::string own = read_file(folder / "own.vtp");
  const std::size_t start = own.find('_', own.find("<AppendedData")) + 1;
  for (std::size_t b = 8; b < 24; ++b)
    own[start + b] = static_cast<char>(b % 8 == 4 ? 0x01 : 0x00);
  const std::string raw_message = message("raw.vtp", own);
  EXPECT_NE(raw_message.find(": expected a compression header the file can hold, found block 0 of "
                             "4294967296 bytes compressed into "),
            std::string::npos)
      << raw_message;
}

// .vtp files are read through VTK's XML parser but not its reader, which crashed on fuzzed files
// (an array of unknown type, string field data read as raw bytes): the points and polygons of
// every storage VTK writes, and polygons that leave the file's points or connectivity refused.
TEST(MeshFile, VtpPolygonsOfEveryStorageAreReadAndBadIndicesRefused) {
  const fs::path data = fs::path(PHANTASM_SOURCE_DIR) / "tests/data/meshes";
  const TriangleMesh expected = read_triangle_mesh(data / "tetrahedron-ascii.vtp");
  ASSERT_EQ(expected.vertex_count(), 4);
  ASSERT_EQ(expected.face_count(), 4);
  EXPECT_NEAR(enclosed_volume(expected), 1.0 / 6.0, 1e-12);
  for (const char* name : {"tetrahedron-inline-zlib.vtp", "tetrahedron-appended-base64-lzma-bigendian.vtp"}) {
    const TriangleMesh mesh = read_triangle_mesh(data / name);
    EXPECT_EQ(mesh.vertices, expected.vertices) << name;
    EXPECT_EQ(mesh.faces, expected.faces) << name;
  }
  const std::string text = read_file(data / "tetrahedron-ascii.vtp");
  const fs::path folder = fresh_folder("mesh-vtp-polygons");
  const auto message = [&](const std::string& name, const std::string& edited) {
    write_text_file(folder / name, edited);
    return input_error_message([&] { read_triangle_mesh(folder / name); });
  };
  EXPECT_EQ(message("index.vtp", replaced(text, "1 2 3 0 3 2", "1 2 3 0 3 7")),
            (folder / "index.vtp").string() +
                ": piece 0 polygon 3: expected vertex indices that refer to the "
                "piece's 4 points, found 7");
  EXPECT_NE(message("offsets.vtp", replaced(text, "3 6 9 12", "3 9 6 12"))
                .find(": piece 0 polygon 2: expected a whole offset from 9 and at most "),
            std::string::npos);
  EXPECT_EQ(message("short.vtp", replaced(text, "3 6 9 12", "3 6 9 14")),
            (folder / "short.vtp").string() + ": piece 0 polygon connectivity: expected 14 values, found 12");
  EXPECT_EQ(message("grid.vtp", replaced(text, "type=\"PolyData\"", "type=\"UnstructuredGrid\"")),
            (folder / "grid.vtp").string() +
                ": expected a VTK XML file of type PolyData, found type 'UnstructuredGrid'");
}

// Tet meshes are read by phantasm's own VTK XML reading too (not vtkXMLUnstructuredGridReader,
// which crashes on some damaged files): ASCII and compressed appended files give the same mesh, and
// a cell that is not a tetrahedron, an index beyond the points or missing types are named.
TEST(MeshFile, VtuCellsAreReadWithoutVtksReaderAndBadCellsRefused) {
  const std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "<UnstructuredGrid><Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
      "<FieldData><Array type=\"String\" Name=\"note\" NumberOfTuples=\"1\" format=\"ascii\">104 105 "
      "0</Array>"
      "</FieldData>\n"
      "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
      "0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>\n"
      "<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>\n"
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
      "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n"
      "</Piece></UnstructuredGrid></VTKFile>\n";
  const fs::path folder = fresh_folder("mesh-vtu-cells");
  write_text_file(folder / "tet.vtu", text);
  const TetMesh tet = read_vtu(folder / "tet.vtu");
  ASSERT_EQ(tet.tets.rows(), 1);
  EXPECT_EQ(tet.vertices.row(3), Eigen::RowVector3d(0, 0, 1));
  EXPECT_NEAR(tet_volume(tet, 0), 1.0 / 6.0, 1e-15);
  // The same mesh written by VTK (appended, zlib) reads back to the same numbers.
  write_vtu(folder / "written.vtu", tet);
  const TetMesh written = read_vtu(folder / "written.vtu");
  EXPECT_EQ(written.vertices, tet.vertices);
  EXPECT_EQ(written.tets, tet.tets);
  const auto message = [&](const std::string& name, const std::string& edited) {
    write_text_file(folder / name, edited);
    return input_error_message([&] { read_vtu(folder / name); });
  };
  EXPECT_EQ(
      message("triangle.vtu", replaced(replaced(text, ">0 1 2 3<", ">0 1 2<"), ">4<", ">3<")),
      (folder / "triangle.vtu").string() +
          ": expected tetrahedra (VTK type 10, 4 vertices), found cell 0 of VTK type 10 with 3 vertices");
  EXPECT_EQ(
      message("type.vtu", replaced(text, ">10<", ">5<")),
      (folder / "type.vtu").string() +
          ": expected tetrahedra (VTK type 10, 4 vertices), found cell 0 of VTK type 5 with 4 vertices");
  EXPECT_EQ(message("index.vtu", replaced(text, ">0 1 2 3<", ">0 1 2 9<")),
            (folder / "index.vtu").string() +
                ": piece 0 cell 0: expected vertex indices that refer to the piece's 4 points, found 9");
  TetMesh not_finite = tet;
  not_finite.vertices(1, 0) = std::numeric_limits<double>::quiet_NaN();
  write_vtu(folder / "nan.vtu", not_finite);
  EXPECT_NE(input_error_message([&] {
              read_vtu(folder / "nan.vtu");
            }).find("nan.vtu: expected finite point coordinates, found point 1 at "),
            std::string::npos);
  EXPECT_EQ(message("types.vtu", replaced(text, "Name=\"types\"", "Name=\"kinds\"")),
            (folder / "types.vtu").string() + ": piece 0: expected the cells' types, found none");
  EXPECT_EQ(message("polydata.vtu", replaced(text, "type=\"UnstructuredGrid\"", "type=\"PolyData\"")),
            (folder / "polydata.vtu").string() +
                ": expected a VTK XML file of type UnstructuredGrid, found type 'PolyData'");
}

// VTK's XML reader dereferences the array it cannot make for an unknown type (a fuzzed file).
TEST(MeshFile, VtkXmlArraysOfUnknownTypeOrFormatAreRefused) {
  const std::string text =
      read_file(fs::path(PHANTASM_SOURCE_DIR) / "tests/data/meshes/tetrahedron-inline-zlib.vtp");
  const fs::path folder = fresh_folder("mesh-vtk-types");
  write_text_file(folder / "type.vtp", replaced(text, "type=\"Float32\"", "type=\"Str)ng\""));
  EXPECT_EQ(
      input_error_message([&] { read_triangle_mesh(folder / "type.vtp"); }),
      (folder / "type.vtp").string() +
          ": array 'Points': expected a type of Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, "
          "Float32, Float64 or String, found 'Str)ng'");
  write_text_file(folder / "format.vtp", replaced(text, "format=\"binary\"", "format=\"appenhed\""));
  EXPECT_EQ(input_error_message([&] { read_triangle_mesh(folder / "format.vtp"); }),
            (folder / "format.vtp").string() +
                ": array 'Points': expected the format ascii, binary or appended, found 'appenhed'");
}
