// VTK XML files (.vtp, .vtu) read without trusting what they declare.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// Refuses a VTK XML file (.vtp, .vtu) that declares more than its bytes can hold or that VTK's
/// reader would crash on: VTK allocates what a file declares before it reads any data, so a file
/// of a few hundred bytes could ask for gigabytes. Checked: every array's type (a numeric type or
/// String) and format (ascii, binary or appended); the point and cell counts of every piece and
/// the tuples of every array (at most what the file's bytes decode to, a compressed byte
/// expanding at most 8192 times); and the header of every compressed array, inline or appended,
/// raw or base64 (blocks that fit in the file, each block's size at most what its compressed
/// bytes can expand to). Files VTK's XML parser cannot parse are left to the caller's reader.
/// @throws InputError naming the file, the element or array, what was expected and what was found
void check_vtk_xml_sizes(const std::filesystem::path& path);

/// The points and polygons of a VTK XML PolyData file (.vtp), every piece, with their vertex
/// indices into `points` (pieces after the first offset by the points before them).
struct VtpPolygons {
  std::vector<double> points; ///< x, y, z of each point, as the file holds them
  std::vector<std::vector<long long>> polygons;
};

/// Reads the points and polygons of a .vtp file (ASCII, inline base64 or appended raw or base64
/// data; uncompressed, zlib, LZ4 or LZMA) through VTK's XML parser and decompressors, after
/// check_vtk_xml_sizes' checks. VTK's own reader is not used: it crashes on some damaged files
/// (string arrays of field data, arrays of unknown types) and reads arrays a mesh does not need.
/// Verts, lines, strips, field, point and cell data are ignored.
/// @throws InputError naming the file, the piece or array, what was expected and what was found
VtpPolygons read_vtp_polygons(const std::filesystem::path& path);

/// A numeric array of a file's cell data, the values of every piece in turn.
struct VtuCellArray {
  std::string name;
  int components = 1;
  std::vector<double> values; ///< #cells * components, cell-major, as doubles (exact for Int32)
};

/// The points and cells of a VTK XML UnstructuredGrid file (.vtu), every piece, with their
/// vertex indices into `points` and each cell's VTK type.
struct VtuCells {
  std::vector<double> points; ///< x, y, z of each point, as the file holds them
  std::vector<std::vector<long long>> cells;
  std::vector<int> types;                ///< VTK cell type of each cell (10: tetrahedron)
  std::vector<VtuCellArray> cell_arrays; ///< only when asked for, in the file's order
};

/// Reads the points and cells of a .vtu file as read_vtp_polygons reads a .vtp file (the same
/// storages and checks, VTK's XML parser and decompressors, not its reader); the cell types must
/// be whole numbers from 0 to 255. Point and field data are ignored, and so is cell data unless
/// `with_cell_arrays`: then its numeric arrays are read (those every piece with cells holds, with
/// the same components; string arrays are passed over).
/// @throws InputError naming the file, the piece or array, what was expected and what was found
VtuCells read_vtu_cells(const std::filesystem::path& path, bool with_cell_arrays = false);

} // namespace phantasm
