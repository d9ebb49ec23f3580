// Mesh files through VTK: the only place besides the other io adapters that includes it.

#include "io/mesh_file.hpp"

#include "core/error.hpp"
#include "geometry/tet_boundary.hpp"
#include "io/atomic_file.hpp"

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDataObject.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>

namespace phantasm {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& message) {
  throw InputError(path.string() + ": " + message);
}

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

void check_readable(const std::filesystem::path& path, const char* what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    fail(path, std::string("expected ") + what + ", found no such file");
  if (std::filesystem::file_size(path, error) == 0)
    fail(path, std::string("expected ") + what + ", found an empty file");
}

/// Refuses a binary STL file whose triangle count (the 4 bytes after its 80-byte header) is more
/// than the file holds: vtkSTLReader allocates the points of that many triangles before it reads
/// any (a 100-byte file could ask for 100 GB). A count below the file's triangles is left to VTK,
/// which reads them all (exporters that write 0 exist). vtkSTLReader's own test tells binary
/// from ASCII files.
void check_binary_stl_count(const std::filesystem::path& path) {
  if (vtksys::SystemTools::DetectFileType(path.c_str()) == vtksys::SystemTools::FileTypeText) return;
  std::ifstream in(path, std::ios::binary);
  unsigned char header[84] = {};
  if (!in.read(reinterpret_cast<char*>(header), sizeof header)) return; // too short: VTK refuses it
  const std::uint64_t count = std::uint64_t{header[80]} | std::uint64_t{header[81]} << 8 |
                              std::uint64_t{header[82]} << 16 | std::uint64_t{header[83]} << 24;
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (!error && 84 + 50 * count > size) {
    fail(path, "expected a binary STL file of 84 + 50 bytes per triangle (" +
                   std::to_string(84 + 50 * count) + " bytes for the " + std::to_string(count) +
                   " triangles its header counts), found " + std::to_string(size) + " bytes");
  }
}

/// Runs a VTK reader with VTK's own messages silenced (they would go to stderr as warnings
/// the user cannot act on); failures are judged from the output.
template <typename Reader>
vtkSmartPointer<vtkPolyData> read_poly_data(const std::filesystem::path& path) {
  vtkNew<Reader> reader;
  reader->SetFileName(path.c_str());
  reader->GlobalWarningDisplayOff();
  reader->Update();
  vtkSmartPointer<vtkPolyData> data = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !data) fail(path, "expected a mesh file, found one VTK cannot read");
  return data;
}

vtkSmartPointer<vtkPoints> make_points(const Eigen::MatrixX3d& vertices) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(vertices.rows());
  for (Eigen::Index i = 0; i < vertices.rows(); ++i)
    points->SetPoint(i, vertices(i, 0), vertices(i, 1), vertices(i, 2));
  return points;
}

void add_point_arrays(vtkPointData* data, const std::vector<PointArray>& arrays, Eigen::Index vertex_count,
                      const std::filesystem::path& path) {
  for (const PointArray& array : arrays) {
    if (array.components < 1 || array.values.size() != static_cast<std::size_t>(vertex_count) *
                                                           static_cast<std::size_t>(array.components)) {
      throw std::invalid_argument(path.string() + ": point array " + array.name + " has " +
                                  std::to_string(array.values.size()) + " values for " +
                                  std::to_string(vertex_count) + " vertices");
    }
    vtkNew<vtkDoubleArray> values;
    values->SetName(array.name.c_str());
    values->SetNumberOfComponents(array.components);
    values->SetNumberOfTuples(vertex_count);
    std::copy(array.values.begin(), array.values.end(), values->GetPointer(0));
    data->AddArray(values);
  }
}

void add_string(vtkFieldData* data, const std::string& name, const std::string& value) {
  vtkNew<vtkStringArray> array;
  array->SetName(name.c_str());
  array->InsertNextValue(value);
  data->AddArray(array);
}

/// The frame and units of the points and of every point array, as field data: a mesh's
/// displacement is in RAS like its points, while the NIfTI fields are in LPS, and only the file
/// can tell a reader which it holds.
void add_frames_and_units(vtkDataObject& object, const std::vector<PointArray>& arrays) {
  vtkFieldData* data = object.GetFieldData();
  // 3D Slicer reads the points' frame from a field named SPACE (and takes LPS without it).
  add_string(data, "SPACE", "RAS");
  add_string(data, "Points_frame", "RAS");
  add_string(data, "Points_units", "mm");
  for (const PointArray& array : arrays) {
    add_string(data, array.name + "_frame", array.frame);
    add_string(data, array.name + "_units", array.units);
  }
  add_string(data, "conventions",
             "phantasm: points in world RAS millimetres (+x right, +y anterior, +z superior), as the NIfTI "
             "affines; each point array's frame and units are in <array>_frame and <array>_units (vector "
             "components in RAS, unlike the NIfTI displacement fields, whose components are LPS)");
}

/// Configures an XML writer for compact, deterministic output into a string.
template <typename Writer>
void write_xml(Writer& writer, const std::filesystem::path& path) {
  writer.SetDataModeToAppended();
  writer.EncodeAppendedDataOff();
  writer.SetCompressorTypeToZLib();
  writer.SetHeaderTypeToUInt64();
  writer.WriteToOutputStringOn();
  if (writer.Write() != 1) throw std::runtime_error(path.string() + ": VTK could not encode the mesh");
  write_file_atomically(path, writer.GetOutputString());
}

} // namespace

TriangleMesh read_triangle_mesh(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  const char* what = "a triangle mesh (.stl, .obj, .ply or .vtp)";
  vtkSmartPointer<vtkPolyData> data;
  if (extension == ".stl") {
    check_readable(path, what);
    check_binary_stl_count(path);
    data = read_poly_data<vtkSTLReader>(path);
  } else if (extension == ".obj") {
    check_readable(path, what);
    data = read_poly_data<vtkOBJReader>(path);
  } else if (extension == ".ply") {
    check_readable(path, what);
    data = read_poly_data<vtkPLYReader>(path);
  } else if (extension == ".vtp") {
    check_readable(path, what);
    data = read_poly_data<vtkXMLPolyDataReader>(path);
  } else {
    fail(path, std::string("expected ") + what + ", found extension '" + extension + "'");
  }
  // Keep only polygons, as triangles (VTK keeps the points as they are).
  vtkNew<vtkPolyData> polygons;
  polygons->SetPoints(data->GetPoints());
  polygons->SetPolys(data->GetPolys());
  vtkNew<vtkTriangleFilter> triangles;
  triangles->SetInputData(polygons);
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkPolyData* result = triangles->GetOutput();
  if (!result->GetPolys() || result->GetPolys()->GetNumberOfCells() == 0 || !result->GetPoints())
    fail(path, "expected triangles, found none");

  // Merge exactly coincident points and drop unused ones, keeping the file's order otherwise.
  vtkCellArray* cells = result->GetPolys();
  TriangleMesh mesh;
  mesh.faces.resize(cells->GetNumberOfCells(), 3);
  vtkNew<vtkIdList> ids;
  Eigen::Index f = 0;
  for (cells->InitTraversal(); cells->GetNextCell(ids);) {
    if (ids->GetNumberOfIds() != 3)
      fail(path, "expected triangles, found a cell of " + std::to_string(ids->GetNumberOfIds()) + " points");
    for (int k = 0; k < 3; ++k)
      mesh.faces(f, k) = static_cast<int>(ids->GetId(k));
    ++f;
  }
  std::vector<int> merged(static_cast<std::size_t>(result->GetNumberOfPoints()), -1);
  for (Eigen::Index i = 0; i < mesh.faces.size(); ++i)
    merged[static_cast<std::size_t>(mesh.faces.data()[i])] = 0; // used
  std::map<std::array<double, 3>, int> first_of_position;
  std::vector<std::array<double, 3>> kept;
  for (std::size_t id = 0; id < merged.size(); ++id) {
    if (merged[id] < 0) continue;
    std::array<double, 3> p;
    result->GetPoint(static_cast<vtkIdType>(id), p.data());
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      fail(path, "expected finite coordinates, found a NaN or infinity at point " + std::to_string(id));
    const auto [it, inserted] = first_of_position.try_emplace(p, static_cast<int>(kept.size()));
    if (inserted) kept.push_back(p);
    merged[id] = it->second;
  }
  for (Eigen::Index i = 0; i < mesh.faces.size(); ++i)
    mesh.faces.data()[i] = merged[static_cast<std::size_t>(mesh.faces.data()[i])];
  mesh.vertices.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t i = 0; i < kept.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = Eigen::RowVector3d(kept[i][0], kept[i][1], kept[i][2]);
  return mesh;
}

void write_vtp(const std::filesystem::path& path, const TriangleMesh& mesh,
               const std::vector<PointArray>& arrays) {
  vtkNew<vtkPolyData> data;
  data->SetPoints(make_points(mesh.vertices));
  vtkNew<vtkCellArray> polys;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    const vtkIdType ids[3] = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
    polys->InsertNextCell(3, ids);
  }
  data->SetPolys(polys);
  add_point_arrays(data->GetPointData(), arrays, mesh.vertices.rows(), path);
  add_frames_and_units(*data, arrays);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(data);
  write_xml(*writer, path);
}

void write_vtu(const std::filesystem::path& path, const TetMesh& mesh,
               const std::vector<PointArray>& arrays) {
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(make_points(mesh.vertices));
  grid->Allocate(mesh.tets.rows());
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const vtkIdType ids[4] = {mesh.tets(t, 0), mesh.tets(t, 1), mesh.tets(t, 2), mesh.tets(t, 3)};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  add_point_arrays(grid->GetPointData(), arrays, mesh.vertices.rows(), path);
  add_frames_and_units(*grid, arrays);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetInputData(grid);
  write_xml(*writer, path);
}

TetMesh read_vtu(const std::filesystem::path& path) {
  check_readable(path, "a tetrahedral mesh (.vtu)");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->GlobalWarningDisplayOff();
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !grid || grid->GetNumberOfCells() == 0)
    fail(path, "expected a VTK unstructured grid of tetrahedra, found none");
  TetMesh mesh;
  mesh.vertices.resize(grid->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) {
    double p[3];
    grid->GetPoint(i, p);
    mesh.vertices.row(i) = Eigen::RowVector3d(p[0], p[1], p[2]);
  }
  mesh.tets.resize(grid->GetNumberOfCells(), 4);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA)
      fail(path, "expected tetrahedra, found cell " + std::to_string(c) + " of VTK type " +
                     std::to_string(grid->GetCellType(c)));
    grid->GetCellPoints(c, ids);
    for (int k = 0; k < 4; ++k)
      mesh.tets(c, k) = static_cast<int>(ids->GetId(k));
  }
  mesh.boundary_faces = tet_boundary_faces(mesh.vertices, mesh.tets);
  return mesh;
}

} // namespace phantasm
