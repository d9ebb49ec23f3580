// Mesh files through VTK: the only place besides the other io adapters that includes it. OBJ and
// PLY files are parsed here (VTK's readers of them crash on faces that name missing vertices).

#include "io/mesh_file.hpp"
#include "io/vtk_ready.hpp"

#include "core/abandonable_work.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/path_kind.hpp"
#include "geometry/tet_boundary.hpp"
#include "io/atomic_file.hpp"
#include "io/file_error.hpp"
#include "io/vtk_xml_file.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataObject.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

namespace phantasm {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

void check_readable(const std::filesystem::path& path, const char* what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw_file_error(path, std::string("expected ") + what + ", found " + path_kind(path));
  if (std::filesystem::file_size(path, error) == 0)
    throw_file_error(path, std::string("expected ") + what + ", found an empty file");
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
    throw_file_error(path, "expected a binary STL file of 84 + 50 bytes per triangle (" +
                               std::to_string(84 + 50 * count) + " bytes for the " + std::to_string(count) +
                               " triangles its header counts), found " + std::to_string(size) + " bytes");
  }
}

/// Polygons of a mesh file, as phantasm's own OBJ and PLY readers read them (VTK's readers of
/// these formats crash on faces that name missing vertices): points as float, as VTK keeps
/// them, and faces of at least three indices into the points.
struct Polygons {
  std::vector<std::array<float, 3>> points;
  std::vector<std::vector<vtkIdType>> faces;
  std::vector<std::string> face_places; ///< where each face is in the file, for messages
};

/// A coordinate as float, as VTK's readers store points; beyond float's range, infinity (which
/// the coordinate checks refuse), since converting such a double is undefined.
float to_float(double x) {
  if (std::isfinite(x) && std::abs(x) > std::numeric_limits<float>::max())
    return std::copysign(std::numeric_limits<float>::infinity(), x);
  return static_cast<float>(x);
}

/// A whole token as a number (strtod's syntax), or nothing.
std::optional<double> parse_number(const std::string& token) {
  if (token.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size()) return std::nullopt;
  return value;
}

/// Checks every face's indices against the points and makes the VTK polygons.
vtkSmartPointer<vtkPolyData> to_poly_data(const std::filesystem::path& path, const Polygons& polygons) {
  vtkNew<vtkPoints> points;
  points->SetNumberOfPoints(static_cast<vtkIdType>(polygons.points.size()));
  for (std::size_t i = 0; i < polygons.points.size(); ++i)
    points->SetPoint(static_cast<vtkIdType>(i), polygons.points[i].data());
  vtkNew<vtkCellArray> cells;
  const auto count = static_cast<vtkIdType>(polygons.points.size());
  for (std::size_t f = 0; f < polygons.faces.size(); ++f) {
    for (const vtkIdType id : polygons.faces[f]) {
      if (id < 0 || id >= count)
        throw_file_error(path, polygons.face_places[f] +
                                   ": expected vertex indices that refer to the file's " +
                                   std::to_string(count) + " vertices, found one of vertex " +
                                   std::to_string(id) + " (counted from 0)");
    }
    cells->InsertNextCell(static_cast<vtkIdType>(polygons.faces[f].size()), polygons.faces[f].data());
  }
  vtkNew<vtkPolyData> data;
  data->SetPoints(points);
  data->SetPolys(cells);
  return data;
}

/// Wavefront OBJ: `v x y z` vertices and `f` faces of 1-based indices (negative ones count back
/// from the last vertex so far; `i/t/n` forms keep i); every other statement is skipped.
vtkSmartPointer<vtkPolyData> read_obj(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  Polygons polygons;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    if (const auto comment = line.find('#'); comment != std::string::npos) line.resize(comment);
    std::istringstream words(line);
    std::string keyword, word;
    if (!(words >> keyword)) continue;
    const std::string place = "line " + std::to_string(number);
    if (keyword == "v") {
      std::array<float, 3> p{};
      for (float& x : p) {
        const std::optional<double> value = words >> word ? parse_number(word) : std::nullopt;
        if (!value)
          throw_file_error(path, place + ": expected 'v x y z' (three numbers), found '" + line + "'");
        x = to_float(*value);
      }
      polygons.points.push_back(p);
    } else if (keyword == "f") {
      std::vector<vtkIdType> face;
      while (words >> word) {
        const std::string index_text = word.substr(0, word.find('/'));
        long long index = 0;
        const auto [end, error] =
            std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
        if (error != std::errc() || end != index_text.data() + index_text.size() || index == 0 ||
            index < -static_cast<long long>(polygons.points.size()) || index > (1ll << 40))
          throw_file_error(
              path,
              place + ": expected vertex indices from 1 (or back from -1, the last vertex so far), found '" +
                  word + "'");
        face.push_back(static_cast<vtkIdType>(
            index < 0 ? static_cast<long long>(polygons.points.size()) + index : index - 1));
      }
      if (face.size() < 3)
        throw_file_error(path, place + ": expected a face of at least 3 vertices, found " +
                                   std::to_string(face.size()));
      polygons.faces.push_back(std::move(face));
      polygons.face_places.push_back(place);
    }
  }
  return to_poly_data(path, polygons);
}

/// The value types of PLY properties.
enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<PlyType> ply_type(const std::string& name) {
  static const std::map<std::string, PlyType> types = {
      {"char", PlyType::int8},      {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},    {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16},  {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},    {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32},  {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  const auto found = types.find(name);
  if (found == types.end()) return std::nullopt;
  return found->second;
}

std::size_t ply_size(PlyType type) {
  switch (type) {
  case PlyType::int8:
  case PlyType::uint8: return 1;
  case PlyType::int16:
  case PlyType::uint16: return 2;
  case PlyType::int32:
  case PlyType::uint32:
  case PlyType::float32: return 4;
  case PlyType::float64: return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;
  bool list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

/// Reads the values of a PLY body: whitespace-separated numbers (ascii) or packed binary values.
class PlyValues {
public:
  PlyValues(const std::filesystem::path& path, const std::string& bytes, std::size_t at, int format)
      : m_path(path), m_bytes(bytes), m_at(at), m_format(format) {}

  double next(PlyType type, const std::string& place) {
    if (m_format == 0) {
      while (m_at < m_bytes.size() && std::isspace(static_cast<unsigned char>(m_bytes[m_at])))
        ++m_at;
      const std::size_t start = m_at;
      while (m_at < m_bytes.size() && !std::isspace(static_cast<unsigned char>(m_bytes[m_at])))
        ++m_at;
      const std::string token = m_bytes.substr(start, m_at - start);
      const std::optional<double> value = parse_number(token);
      if (!value)
        throw_file_error(m_path, place + ": expected a number, found " +
                                     (token.empty() ? "the end of the file" : "'" + token + "'"));
      return *value;
    }
    const std::size_t size = ply_size(type);
    if (m_bytes.size() - m_at < size)
      throw_file_error(m_path, place + ": expected more values, found the end of the file");
    unsigned char raw[8];
    std::memcpy(raw, m_bytes.data() + m_at, size);
    m_at += size;
    const std::uint16_t one = 1;
    const bool native_little = *reinterpret_cast<const unsigned char*>(&one) == 1;
    if ((m_format == 1) != native_little) std::reverse(raw, raw + size);
    switch (type) {
    case PlyType::int8: return static_cast<double>(static_cast<std::int8_t>(raw[0]));
    case PlyType::uint8: return raw[0];
    case PlyType::int16: return load<std::int16_t>(raw);
    case PlyType::uint16: return load<std::uint16_t>(raw);
    case PlyType::int32: return load<std::int32_t>(raw);
    case PlyType::uint32: return load<std::uint32_t>(raw);
    case PlyType::float32: return load<float>(raw);
    case PlyType::float64: return load<double>(raw);
    }
    return 0.0;
  }
  std::size_t remaining() const { return m_bytes.size() - m_at; }

private:
  template <typename T>
  static double load(const unsigned char* raw) {
    T value;
    std::memcpy(&value, raw, sizeof value);
    return static_cast<double>(value);
  }

  const std::filesystem::path& m_path;
  const std::string& m_bytes;
  std::size_t m_at;
  int m_format; ///< 0 ascii, 1 binary little endian, 2 binary big endian
};

/// A PLY header: its elements, the body's format (0 ascii, 1 binary little endian, 2 binary big
/// endian) and where the body starts.
struct PlyHeader {
  std::vector<PlyElement> elements;
  int format = -1;
  std::size_t body = 0;
};

/// A header line's property (the words after 'property'), of the element before it.
PlyProperty read_ply_property(const std::filesystem::path& path, const std::string& place,
                              const std::string& line, std::istringstream& words) {
  std::string a, b, c, d;
  words >> a;
  if (a == "list") {
    words >> b >> c >> d;
    const auto count_type = ply_type(b), item_type = ply_type(c);
    if (!count_type || !item_type || d.empty() || *count_type == PlyType::float32 ||
        *count_type == PlyType::float64)
      throw_file_error(
          path, place + ": expected 'property list COUNT_TYPE ITEM_TYPE NAME' (integer count), found '" +
                    line + "'");
    return PlyProperty{d, *item_type, true, *count_type};
  }
  words >> b;
  const auto type = ply_type(a);
  if (!type || b.empty())
    throw_file_error(path, place + ": expected 'property TYPE NAME', found '" + line + "'");
  return PlyProperty{b, *type, false, PlyType::uint8};
}

/// Reads a header line after the first (format, element, property or a comment) into `header`.
void read_ply_header_line(const std::filesystem::path& path, const std::string& bytes,
                          const std::string& line, const std::string& place, const std::string& keyword,
                          std::istringstream& words, PlyHeader* header) {
  if (keyword.empty() || keyword == "comment" || keyword == "obj_info") return;
  std::string a, b;
  if (keyword == "format") {
    words >> a >> b;
    header->format = a == "ascii" ? 0 : a == "binary_little_endian" ? 1 : a == "binary_big_endian" ? 2 : -1;
    if (header->format < 0 || b != "1.0")
      throw_file_error(
          path, place + ": expected 'format ascii|binary_little_endian|binary_big_endian 1.0', found '" +
                    line + "'");
  } else if (keyword == "element") {
    words >> a >> b;
    std::uint64_t count = 0;
    const auto [end_of_count, error] = std::from_chars(b.data(), b.data() + b.size(), count);
    // Every element takes at least a byte: a count beyond the file's size is not a mesh.
    if (a.empty() || error != std::errc() || end_of_count != b.data() + b.size() || count > bytes.size())
      throw_file_error(path, place +
                                 ": expected 'element NAME COUNT' with a count the file can hold (at most " +
                                 std::to_string(bytes.size()) + "), found '" + line + "'");
    header->elements.push_back(PlyElement{a, count, {}});
  } else if (keyword == "property") {
    if (header->elements.empty())
      throw_file_error(path, place + ": expected 'element' before its properties, found '" + line + "'");
    header->elements.back().properties.push_back(read_ply_property(path, place, line, words));
  } else {
    throw_file_error(path,
                     place +
                         ": expected a PLY header keyword (format, element, property, comment, end_header), "
                         "found '" +
                         keyword + "'");
  }
}

/// The header of a PLY file's bytes, up to its 'end_header' line.
PlyHeader read_ply_header(const std::filesystem::path& path, const std::string& bytes) {
  PlyHeader header;
  std::size_t at = 0;
  for (std::size_t number = 1;; ++number) {
    const std::size_t end = bytes.find('\n', at);
    if (end == std::string::npos)
      throw_file_error(path, "expected a PLY header ending in 'end_header', found none");
    std::string line = bytes.substr(at, end - at);
    at = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string place = "header line " + std::to_string(number);
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (number == 1) {
      if (line != "ply") throw_file_error(path, "expected 'ply' on the first line, found '" + line + "'");
      continue;
    }
    if (keyword == "end_header") break;
    read_ply_header_line(path, bytes, line, place, keyword, words, &header);
  }
  if (header.format < 0) throw_file_error(path, "expected a 'format' line in the PLY header, found none");
  header.body = at;
  return header;
}

/// Reads an element's values: the points of element `vertex` and the faces of element `face`
/// into `polygons`; other elements are read past.
void read_ply_element(const std::filesystem::path& path, const std::string& bytes, const PlyElement& element,
                      PlyValues& values, Polygons* polygons) {
  const bool vertex = element.name == "vertex", face = element.name == "face";
  int xyz[3] = {-1, -1, -1};
  int indices = -1;
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& property = element.properties[p];
    for (int c = 0; c < 3 && vertex; ++c)
      if (!property.list && property.name == std::string(1, static_cast<char>('x' + c)))
        xyz[c] = static_cast<int>(p);
    if (face && property.list && (property.name == "vertex_indices" || property.name == "vertex_index"))
      indices = static_cast<int>(p);
  }
  if (vertex && element.count > 0 && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) {
    std::string found;
    for (const PlyProperty& property : element.properties)
      found += (found.empty() ? "" : ", ") + property.name;
    throw_file_error(path, "expected properties x, y and z of element 'vertex', found " +
                               (found.empty() ? "none" : found));
  }
  if (face && element.count > 0 && indices < 0)
    throw_file_error(path, "expected a list property 'vertex_indices' of element 'face', found none");
  for (std::uint64_t e = 0; e < element.count; ++e) {
    const std::string place = "element " + element.name + " " + std::to_string(e);
    std::array<float, 3> point{};
    std::vector<vtkIdType> polygon;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      if (!property.list) {
        const double value = values.next(property.type, place);
        for (int c = 0; c < 3; ++c)
          if (static_cast<int>(p) == xyz[c]) point[c] = to_float(value);
        continue;
      }
      const double count = values.next(property.count_type, place);
      if (!(count >= 0.0) || count != std::floor(count) || count > static_cast<double>(values.remaining()))
        throw_file_error(path,
                         place + ": expected a list length the file can hold, found " + format_number(count));
      for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
        const double item = values.next(property.type, place);
        if (static_cast<int>(p) != indices) continue;
        if (!(item >= 0.0) || item != std::floor(item) || item > static_cast<double>(bytes.size()))
          throw_file_error(path, place + ": expected vertex indices (whole numbers from 0), found " +
                                     format_number(item));
        polygon.push_back(static_cast<vtkIdType>(item));
      }
    }
    if (vertex) polygons->points.push_back(point);
    if (face) {
      if (polygon.size() < 3)
        throw_file_error(path, place + ": expected a face of at least 3 vertices, found " +
                                   std::to_string(polygon.size()));
      polygons->faces.push_back(std::move(polygon));
      polygons->face_places.push_back(place);
    }
  }
}

/// Stanford PLY (ascii and binary): the x, y, z of element `vertex` and the index list
/// `vertex_indices` (or `vertex_index`) of element `face`; other elements and properties are read
/// past.
vtkSmartPointer<vtkPolyData> read_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const PlyHeader header = read_ply_header(path, bytes);
  Polygons polygons;
  PlyValues values(path, bytes, header.body, header.format);
  for (const PlyElement& element : header.elements)
    read_ply_element(path, bytes, element, values, &polygons);
  return to_poly_data(path, polygons);
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
  if (reader->GetErrorCode() != 0 || !data)
    throw_file_error(path, "expected a mesh file, found one VTK cannot read");
  return data;
}

/// A .vtp file's points and polygons (read_vtp_polygons, which checks the indices), as VTK data.
vtkSmartPointer<vtkPolyData> read_vtp(const std::filesystem::path& path) {
  const VtpPolygons file = read_vtp_polygons(path);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  const auto count = static_cast<vtkIdType>(file.points.size() / 3);
  points->SetNumberOfPoints(count);
  for (vtkIdType i = 0; i < count; ++i)
    points->SetPoint(i, file.points.data() + 3 * i);
  vtkNew<vtkCellArray> cells;
  for (const std::vector<long long>& polygon : file.polygons) {
    std::vector<vtkIdType> ids(polygon.begin(), polygon.end());
    cells->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
  }
  vtkNew<vtkPolyData> data;
  data->SetPoints(points);
  data->SetPolys(cells);
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

void add_cell_arrays(vtkCellData* data, const std::vector<CellArray>& arrays, Eigen::Index cell_count,
                     const std::filesystem::path& path) {
  for (const CellArray& array : arrays) {
    if (array.values.size() != static_cast<std::size_t>(cell_count)) {
      throw std::invalid_argument(path.string() + ": cell array " + array.name + " has " +
                                  std::to_string(array.values.size()) + " values for " +
                                  std::to_string(cell_count) + " cells");
    }
    if (!array.integer) {
      vtkNew<vtkDoubleArray> values;
      values->SetName(array.name.c_str());
      values->SetNumberOfTuples(cell_count);
      std::copy(array.values.begin(), array.values.end(), values->GetPointer(0));
      data->AddArray(values);
      continue;
    }
    vtkNew<vtkIntArray> values;
    values->SetName(array.name.c_str());
    values->SetNumberOfTuples(cell_count);
    for (std::size_t c = 0; c < array.values.size(); ++c) {
      const double value = array.values[c];
      if (!(value >= std::numeric_limits<int>::min() && value <= std::numeric_limits<int>::max()) ||
          value != std::floor(value)) {
        throw std::invalid_argument(path.string() + ": cell array " + array.name + " holds " +
                                    format_number(value) + " at cell " + std::to_string(c) +
                                    ", expected a whole number within Int32");
      }
      values->SetValue(static_cast<vtkIdType>(c), static_cast<int>(value));
    }
    data->AddArray(values);
  }
}

void add_string(vtkFieldData* data, const std::string& name, const std::string& value) {
  vtkNew<vtkStringArray> array;
  array->SetName(name.c_str());
  array->InsertNextValue(value);
  data->AddArray(array);
}

/// The frame and units of the points and of every point array, and the units and value names of
/// every cell array, as field data: a mesh's displacement is in RAS like its points, while the
/// NIfTI fields are in LPS, and only the file can tell a reader which it holds.
void add_frames_and_units(vtkDataObject& object, const std::vector<PointArray>& arrays,
                          const std::vector<CellArray>& cell_arrays = {}) {
  vtkFieldData* data = object.GetFieldData();
  // 3D Slicer reads the points' frame from a field named SPACE (and takes LPS without it).
  add_string(data, "SPACE", "RAS");
  add_string(data, "Points_frame", "RAS");
  add_string(data, "Points_units", "mm");
  for (const PointArray& array : arrays) {
    add_string(data, array.name + "_frame", array.frame);
    add_string(data, array.name + "_units", array.units);
  }
  for (const CellArray& array : cell_arrays) {
    add_string(data, array.name + "_units", array.units);
    if (array.value_names.empty()) continue;
    vtkNew<vtkIntArray> values;
    values->SetName((array.name + "_values").c_str());
    vtkNew<vtkStringArray> names;
    names->SetName((array.name + "_names").c_str());
    for (const auto& [value, name] : array.value_names) {
      values->InsertNextValue(value);
      names->InsertNextValue(name);
    }
    data->AddArray(values);
    data->AddArray(names);
  }
  std::string conventions =
      "phantasm: points in world RAS millimetres (+x right, +y anterior, +z superior), as the NIfTI "
      "affines; each point array's frame and units are in <array>_frame and <array>_units (vector "
      "components in RAS, unlike the NIfTI displacement fields, whose components are LPS)";
  // Only files with cell arrays say how theirs are described, so that the others keep their bytes.
  if (!cell_arrays.empty())
    conventions += "; each cell array's units are in <array>_units and, for labels, the name of each "
                   "value in <array>_names (the value at the same place in <array>_values)";
  add_string(data, "conventions", conventions);
}

/// Configures an XML writer for compact, deterministic output into a string.
template <typename Writer>
void write_xml(Writer& writer, const std::filesystem::path& path) {
  writer.SetDataModeToAppended();
  writer.EncodeAppendedDataOff();
  writer.SetCompressorTypeToZLib();
  // Level 1 of 9: two to three times as fast as the default 5 on vertex and index arrays, for a
  // few percent more bytes.
  writer.SetCompressionLevel(1);
  writer.SetHeaderTypeToUInt64();
  writer.WriteToOutputStringOn();
  {
    // VTK encodes and compresses the whole mesh in one call that polls nothing (seconds for a
    // million triangles): in memory, so a cancelled run may be abandoned inside it.
    const AbandonableWork encoding;
    if (writer.Write() != 1) throw std::runtime_error(path.string() + ": VTK could not encode the mesh");
  }
  write_file_atomically(path, writer.GetOutputString());
}

} // namespace

TriangleMesh read_triangle_mesh(const std::filesystem::path& path) {
  make_vtk_ready();
  const std::string extension = lower_extension(path);
  const char* what = "a triangle mesh (.stl, .obj, .ply or .vtp)";
  vtkSmartPointer<vtkPolyData> data;
  if (extension == ".stl") {
    check_readable(path, what);
    check_binary_stl_count(path);
    data = read_poly_data<vtkSTLReader>(path);
  } else if (extension == ".obj") {
    check_readable(path, what);
    data = read_obj(path);
  } else if (extension == ".ply") {
    check_readable(path, what);
    data = read_ply(path);
  } else if (extension == ".vtp") {
    check_readable(path, what);
    data = read_vtp(path);
  } else {
    throw_file_error(path, std::string("expected ") + what + ", found extension '" + extension + "'");
  }
  // Keep only polygons, as triangles (VTK keeps the points as they are). Every reader above has
  // checked the polygons' indices against the points (vtkTriangleFilter reads the points of a
  // polygon of more than three corners): the OBJ and PLY readers in to_poly_data, the .vtp reader
  // in read_vtp_polygons; vtkSTLReader makes its triangles from the points it reads.
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
    throw_file_error(path, "expected triangles, found none");

  // Merge exactly coincident points and drop unused ones, keeping the file's order otherwise.
  vtkCellArray* cells = result->GetPolys();
  TriangleMesh mesh;
  mesh.faces.resize(cells->GetNumberOfCells(), 3);
  vtkNew<vtkIdList> ids;
  Eigen::Index f = 0;
  const vtkIdType point_count = result->GetNumberOfPoints();
  for (cells->InitTraversal(); cells->GetNextCell(ids);) {
    if (ids->GetNumberOfIds() != 3)
      throw_file_error(path, "expected triangles, found a cell of " + std::to_string(ids->GetNumberOfIds()) +
                                 " points");
    for (int k = 0; k < 3; ++k) {
      // VTK's readers keep the indices as the file gives them (an OBJ face "f 1 2 9" of a file
      // with three vertices).
      const vtkIdType id = ids->GetId(k);
      if (id < 0 || id >= point_count)
        throw_file_error(path, "triangle " + std::to_string(f) +
                                   ": expected vertex indices that refer to the file's " +
                                   std::to_string(point_count) + " vertices, found index " +
                                   std::to_string(id) + " (from 0)");
      mesh.faces(f, k) = static_cast<int>(id);
    }
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
      throw_file_error(path,
                       "expected finite coordinates, found a NaN or infinity at point " + std::to_string(id));
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
  make_vtk_ready();
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

void write_vtu(const std::filesystem::path& path, const TetMesh& mesh, const std::vector<PointArray>& arrays,
               const std::vector<CellArray>& cell_arrays) {
  make_vtk_ready();
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(make_points(mesh.vertices));
  grid->Allocate(mesh.tets.rows());
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const vtkIdType ids[4] = {mesh.tets(t, 0), mesh.tets(t, 1), mesh.tets(t, 2), mesh.tets(t, 3)};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  add_point_arrays(grid->GetPointData(), arrays, mesh.vertices.rows(), path);
  add_cell_arrays(grid->GetCellData(), cell_arrays, mesh.tets.rows(), path);
  add_frames_and_units(*grid, arrays, cell_arrays);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetInputData(grid);
  write_xml(*writer, path);
}

TetMesh read_vtu(const std::filesystem::path& path) {
  make_vtk_ready();
  check_readable(path, "a tetrahedral mesh (.vtu)");
  check_vtk_xml_sizes(path);
  // Through phantasm's own reading of VTK XML (as .vtp files), not vtkXMLUnstructuredGridReader,
  // which crashes on some damaged files (string field data, arrays of unknown types).
  const VtuCells file = read_vtu_cells(path);
  if (file.cells.empty())
    throw_file_error(path, "expected a VTK unstructured grid of tetrahedra, found no cell");
  TetMesh mesh;
  const auto points = static_cast<Eigen::Index>(file.points.size() / 3);
  if (points > std::numeric_limits<int>::max())
    throw_file_error(path, "expected at most " + std::to_string(std::numeric_limits<int>::max()) +
                               " points, found " + std::to_string(points));
  mesh.vertices.resize(points, 3);
  for (Eigen::Index i = 0; i < points; ++i) {
    mesh.vertices.row(i) =
        Eigen::RowVector3d(file.points[3 * i], file.points[3 * i + 1], file.points[3 * i + 2]);
    if (!mesh.vertices.row(i).allFinite())
      throw_file_error(path, "expected finite point coordinates, found point " + std::to_string(i) + " at " +
                                 format_number(mesh.vertices(i, 0)) + ", " +
                                 format_number(mesh.vertices(i, 1)) + ", " +
                                 format_number(mesh.vertices(i, 2)));
  }
  mesh.tets.resize(static_cast<Eigen::Index>(file.cells.size()), 4);
  for (std::size_t c = 0; c < file.cells.size(); ++c) {
    if (file.types[c] != VTK_TETRA || file.cells[c].size() != 4)
      throw_file_error(path, "expected tetrahedra (VTK type 10, 4 vertices), found cell " +
                                 std::to_string(c) + " of VTK type " + std::to_string(file.types[c]) +
                                 " with " + std::to_string(file.cells[c].size()) + " vertices");
    for (int k = 0; k < 4; ++k)
      mesh.tets(static_cast<Eigen::Index>(c), k) =
          static_cast<int>(file.cells[c][static_cast<std::size_t>(k)]);
  }
  mesh.boundary_faces = tet_boundary_faces(mesh.vertices, mesh.tets);
  return mesh;
}

} // namespace phantasm
