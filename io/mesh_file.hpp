// Triangle and tet mesh files: reading .stl, .obj, .ply and .vtp surfaces, and writing surfaces
// (.vtp) and tet meshes (.vtu) with per-vertex arrays, atomically.
#pragma once

#include "geometry/tet_mesh.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace phantasm {

/// Reads a triangle mesh from .stl (VTK's reader), .vtp (points and polygons through VTK's XML
/// parser, io/vtk_xml_file.hpp), .obj or .ply (read here: `v` and `f` statements; elements
/// `vertex` with x, y, z and `face` with vertex_indices, ascii or binary). Polygons are split into
/// triangles and exactly coincident points merged (STL files repeat them per triangle); points
/// no triangle uses are dropped; otherwise the file's order is kept. Whether the mesh is closed is checked by
/// its user.
/// @throws InputError naming the file: missing, unknown extension, unreadable, no triangles
TriangleMesh read_triangle_mesh(const std::filesystem::path& path);

/// A per-vertex array written with a mesh (ParaView shows it as point data). Its frame and
/// units are written into the file's field data as "<name>_frame" and "<name>_units".
struct PointArray {
  std::string name;
  int components = 1;
  std::vector<double> values; ///< #vertices * components, vertex-major
  std::string frame = "RAS";  ///< the frame of vector components ("RAS": world RAS, as the points)
  std::string units;          ///< e.g. "mm"; empty for a unitless array
};

/// A per-cell array written with a tet mesh (ParaView shows it as cell data), one value per
/// cell: whole numbers (Int32, e.g. labels) or reals (Float64). Its units are written into the
/// file's field data as "<name>_units"; named values (labels) as two arrays of equal length,
/// "<name>_values" (Int32) and "<name>_names" (String), the i-th name naming the i-th value.
struct CellArray {
  std::string name;
  std::vector<double> values; ///< #cells
  bool integer = false;       ///< written as Int32: every value must be a whole number in its range
  std::string units;          ///< empty for a unitless array
  std::vector<std::pair<int, std::string>> value_names; ///< e.g. a label and its organ's name
};

/// Writes a triangle mesh as VTK XML PolyData (.vtp, binary, zlib), atomically; also reads back
/// with read_triangle_mesh. The file's field data state the frame and units of the points
/// ("Points_frame" = "RAS", "Points_units" = "mm", and "SPACE" = "RAS" as 3D Slicer reads it) and
/// of every point array, as one-value string arrays, so that a reader need not know phantasm's
/// conventions.
void write_vtp(const std::filesystem::path& path, const TriangleMesh& mesh,
               const std::vector<PointArray>& arrays = {});

/// Writes a tet mesh as VTK XML UnstructuredGrid (.vtu, binary, zlib), atomically, with field
/// data as write_vtp and, for the cell arrays, as CellArray says. read_vtu_cells
/// (io/vtk_xml_file.hpp) reads the cell arrays back.
/// @throws std::invalid_argument for an array of the wrong length, or an integer array holding a
/// value that is not a whole Int32
void write_vtu(const std::filesystem::path& path, const TetMesh& mesh,
               const std::vector<PointArray>& arrays = {}, const std::vector<CellArray>& cell_arrays = {});

/// Reads a tet mesh written by write_vtu (every cell a VTK_TETRA) through read_vtu_cells
/// (io/vtk_xml_file.hpp), not VTK's reader; boundary faces are recomputed.
/// @throws InputError naming the file
TetMesh read_vtu(const std::filesystem::path& path);

} // namespace phantasm
