// VTK XML files (.vtp, .vtu): the sizes they declare, checked against what the file can hold
// before anything is allocated, and the polygons of a .vtp read through VTK's XML parser and
// decompressors without VTK's readers (io/vtk_xml_file.hpp).

#include "io/vtk_xml_file.hpp"
#include "io/vtk_ready.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "io/file_error.hpp"

#include <vtkBase64InputStream.h>
#include <vtkDataCompressor.h>
#include <vtkInputStream.h>
#include <vtkLZ4DataCompressor.h>
#include <vtkLZMADataCompressor.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>
#include <vtkType.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkZLibDataCompressor.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace phantasm {
namespace {

/// The most a compressed byte can expand to: zlib's limit is 1032, LZ4's 255; LZMA reaches a few
/// thousand on long runs of one byte. Above this a declared size cannot come from the file.
constexpr std::uint64_t k_max_expansion = 8192;
/// Room for a block whose compressed form is all overhead (a few bytes of zeros).
constexpr std::uint64_t k_block_slack = 65536;

/// What the file's root element says about how its binary arrays are stored.
struct Layout {
  std::uint64_t file_size = 0;
  bool compressed = false;
  int header_bytes = 4;       ///< UInt32 (VTK's default) or UInt64 header words
  bool big_endian = false;    ///< byte order of the header words
  std::int64_t appended = -1; ///< file position of the appended data, if any
  bool appended_raw = false;  ///< appended data as raw bytes rather than base64
};

std::uint64_t word(const unsigned char* bytes, const Layout& layout) {
  std::uint64_t value = 0;
  for (int b = 0; b < layout.header_bytes; ++b) {
    const int shift = layout.big_endian ? 8 * (layout.header_bytes - 1 - b) : 8 * b;
    value |= std::uint64_t{bytes[b]} << shift;
  }
  return value;
}

/// Reads `count` header words from a decoder that started reading at the array's data; false
/// when the file ends first (VTK's reader then reports the array as unreadable).
bool read_words(vtkInputStream& stream, std::size_t count, const Layout& layout,
                std::vector<std::uint64_t>& words) {
  std::vector<unsigned char> bytes(count * static_cast<std::size_t>(layout.header_bytes));
  if (stream.Read(bytes.data(), bytes.size()) < bytes.size()) return false;
  words.clear();
  for (std::size_t i = 0; i < count; ++i)
    words.push_back(word(bytes.data() + i * static_cast<std::size_t>(layout.header_bytes), layout));
  return true;
}

/// A compressed array's header (blocks, block size, size of a partial last block, then each
/// block's compressed size) against the file: VTK allocates the sizes it declares.
void check_compression_header(const std::filesystem::path& path, std::ifstream& file, std::int64_t position,
                              bool raw, const Layout& layout, const std::string& array) {
  file.clear();
  file.seekg(position);
  if (!file) return;
  vtkSmartPointer<vtkInputStream> stream;
  if (raw)
    stream = vtkSmartPointer<vtkInputStream>::New();
  else
    stream = vtkSmartPointer<vtkBase64InputStream>::New();
  stream->SetStream(&file);
  stream->StartReading();
  std::vector<std::uint64_t> head;
  if (!read_words(*stream, 3, layout, head)) return;
  const std::uint64_t blocks = head[0], block_size = head[1], last_size = head[2];
  const std::string where = "array " + array + ": expected a compression header the file can hold, found ";
  if (blocks > layout.file_size / static_cast<std::uint64_t>(layout.header_bytes))
    throw_file_error(path, where + std::to_string(blocks) + " blocks in a file of " +
                               std::to_string(layout.file_size) + " bytes");
  // VTK divides by the block size and finds a block by dividing the offset it reads at by it: a
  // block of no bytes, or a last block larger than the others, sends it out of its block list.
  // With no blocks, a last block makes VTK's total size wrap around below zero.
  if (blocks == 0 && last_size != 0)
    throw_file_error(path, where + "no blocks but a last one of " + std::to_string(last_size) + " bytes");
  if (blocks > 0 && (block_size == 0 || last_size > block_size))
    throw_file_error(path, where + "blocks of " + std::to_string(block_size) + " bytes and a last one of " +
                               std::to_string(last_size) +
                               " (blocks of at least a byte, the last one no larger)");
  std::vector<std::uint64_t> sizes;
  if (!read_words(*stream, static_cast<std::size_t>(blocks), layout, sizes)) return;
  stream->EndReading();
  std::uint64_t compressed_so_far = 0; // the blocks follow one another in the file
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t compressed = sizes[b];
    const std::uint64_t uncompressed = (b + 1 == blocks && last_size != 0) ? last_size : block_size;
    compressed_so_far += std::min(compressed, layout.file_size + 1);
    if (compressed_so_far > layout.file_size)
      throw_file_error(path, where + "block " + std::to_string(b) + " of " + std::to_string(compressed) +
                                 " compressed bytes, past the end of a file of " +
                                 std::to_string(layout.file_size) + " bytes");
    if (uncompressed > k_max_expansion * compressed + k_block_slack)
      throw_file_error(path, where + "block " + std::to_string(b) + " of " + std::to_string(uncompressed) +
                                 " bytes compressed into " + std::to_string(compressed) + " (at most " +
                                 std::to_string(k_max_expansion) +
                                 " times as many bytes come out of a compressed one)");
  }
}

/// A count attribute of an element (NumberOfPoints, NumberOfTuples, ...) against the file: each
/// element takes at least `bytes_each` bytes of the decoded data, which a compressed file expands
/// at most k_max_expansion times.
void check_count(const std::filesystem::path& path, vtkXMLDataElement& element, const char* name,
                 std::uint64_t bytes_each, const Layout& layout) {
  long long count = 0;
  if (!element.GetScalarAttribute(name, count)) return;
  const std::uint64_t most =
      (layout.compressed ? k_max_expansion * layout.file_size + k_block_slack : layout.file_size) /
      bytes_each;
  if (count < 0 || static_cast<std::uint64_t>(count) > most) {
    throw_file_error(path, std::string("element ") + element.GetName() + ": expected " + name +
                               " the file can hold (at most " + std::to_string(most) + " in " +
                               std::to_string(layout.file_size) + " bytes), found " + std::to_string(count));
  }
}

bool known_type(const char* type) {
  for (const char* known : {"Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64",
                            "Float32", "Float64", "String"})
    if (std::strcmp(type, known) == 0) return true;
  return false;
}

/// The position of an inline array's data: after its opening tag and the spaces that follow, as
/// VTK's parser finds it.
std::int64_t inline_position(std::ifstream& file, vtkXMLDataElement& element) {
  file.clear();
  file.seekg(element.GetXMLByteIndex());
  char c = 0;
  while (file.get(c) && c != '>') {
  }
  while (file.get(c) && (c == ' ' || c == '\t' || c == '\n' || c == '\r')) {
  }
  if (!file) return -1;
  return static_cast<std::int64_t>(file.tellg()) - 1;
}

void check_element(const std::filesystem::path& path, std::ifstream& file, vtkXMLDataElement& element,
                   const Layout& layout) {
  const char* name = element.GetName();
  if (name != nullptr && std::strcmp(name, "Piece") == 0) {
    // A point takes three values, a cell at least one; a value at least a byte of ASCII text.
    check_count(path, element, "NumberOfPoints", 3, layout);
    for (const char* cells :
         {"NumberOfCells", "NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys"})
      check_count(path, element, cells, 1, layout);
  }
  // Arrays of points, cells and point data are DataArray elements; those of field data, Array.
  if (name != nullptr && (std::strcmp(name, "DataArray") == 0 || std::strcmp(name, "Array") == 0)) {
    check_count(path, element, "NumberOfTuples", 1, layout);
    const char* format = element.GetAttribute("format");
    const char* array_name = element.GetAttribute("Name");
    const std::string array =
        array_name ? std::string("'") + array_name + "'" : std::string("without a name");
    // VTK's reader dereferences the array it fails to make for a type it does not know.
    const char* type = element.GetAttribute("type");
    if (type == nullptr || !known_type(type))
      throw_file_error(path, "array " + array +
                                 ": expected a type of Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, " +
                                 "UInt64, Float32, Float64 or String, found " +
                                 (type ? "'" + std::string(type) + "'" : std::string("none")));
    if (format == nullptr || !(std::strcmp(format, "ascii") == 0 || std::strcmp(format, "binary") == 0 ||
                               std::strcmp(format, "appended") == 0))
      throw_file_error(path, "array " + array + ": expected the format ascii, binary or appended, found " +
                                 (format ? "'" + std::string(format) + "'" : std::string("none")));
    if (layout.compressed && format != nullptr) {
      long long offset = 0;
      if (std::strcmp(format, "appended") == 0 && layout.appended >= 0 &&
          element.GetScalarAttribute("offset", offset) && offset >= 0 &&
          static_cast<std::uint64_t>(offset) < layout.file_size) {
        check_compression_header(path, file, layout.appended + offset, layout.appended_raw, layout, array);
      } else if (std::strcmp(format, "binary") == 0) {
        const std::int64_t position = inline_position(file, element);
        if (position >= 0) check_compression_header(path, file, position, false, layout, array);
      }
    }
  }
  for (int i = 0; i < element.GetNumberOfNestedElements(); ++i)
    check_element(path, file, *element.GetNestedElement(i), layout);
}

vtkXMLDataElement* find_element(vtkXMLDataElement& element, const char* name) {
  if (element.GetName() != nullptr && std::strcmp(element.GetName(), name) == 0) return &element;
  for (int i = 0; i < element.GetNumberOfNestedElements(); ++i) {
    if (vtkXMLDataElement* found = find_element(*element.GetNestedElement(i), name)) return found;
  }
  return nullptr;
}

/// A VTK XML file parsed by VTK's own parser (expat), up to its appended data, with what its
/// root says about how arrays are stored.
struct ParsedFile {
  std::ifstream file;
  vtkNew<vtkXMLDataParser> parser;
  Layout layout;
  vtkXMLDataElement* root = nullptr; ///< null when VTK's parser refused the file
};

void parse(const std::filesystem::path& path, ParsedFile& parsed) {
  std::error_code error;
  parsed.layout.file_size = std::filesystem::file_size(path, error);
  if (error) return;
  parsed.file.open(path, std::ios::binary);
  if (!parsed.file) return;
  parsed.parser->GlobalWarningDisplayOff();
  parsed.parser->SetStream(&parsed.file);
  if (!parsed.parser->Parse() || parsed.parser->GetRootElement() == nullptr) return;
  vtkXMLDataElement& root = *parsed.parser->GetRootElement();
  Layout& layout = parsed.layout;
  layout.compressed = root.GetAttribute("compressor") != nullptr;
  const char* header_type = root.GetAttribute("header_type");
  layout.header_bytes = header_type != nullptr && std::strcmp(header_type, "UInt64") == 0 ? 8 : 4;
  const char* byte_order = root.GetAttribute("byte_order");
  layout.big_endian = byte_order != nullptr && std::strcmp(byte_order, "BigEndian") == 0;
  if (vtkXMLDataElement* appended = find_element(root, "AppendedData")) {
    layout.appended = parsed.parser->GetAppendedDataPosition();
    const char* encoding = appended->GetAttribute("encoding");
    layout.appended_raw = encoding != nullptr && std::strcmp(encoding, "raw") == 0;
  }
  parsed.root = &root;
}

vtkXMLDataElement* child(vtkXMLDataElement& element, const char* name) {
  for (int i = 0; i < element.GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* nested = element.GetNestedElement(i);
    if (nested->GetName() != nullptr && std::strcmp(nested->GetName(), name) == 0) return nested;
  }
  return nullptr;
}

/// The DataArray of `element` named `name`, or the first one when `name` is null.
vtkXMLDataElement* data_array(vtkXMLDataElement& element, const char* name) {
  for (int i = 0; i < element.GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* nested = element.GetNestedElement(i);
    if (nested->GetName() == nullptr || std::strcmp(nested->GetName(), "DataArray") != 0) continue;
    const char* array_name = nested->GetAttribute("Name");
    if (name == nullptr || (array_name != nullptr && std::strcmp(array_name, name) == 0)) return nested;
  }
  return nullptr;
}

/// The VTK word type of a numeric type name, or 0.
int word_type(const char* type) {
  static const std::pair<const char*, int> types[] = {
      {"Int8", VTK_SIGNED_CHAR}, {"UInt8", VTK_UNSIGNED_CHAR},
      {"Int16", VTK_SHORT},      {"UInt16", VTK_UNSIGNED_SHORT},
      {"Int32", VTK_INT},        {"UInt32", VTK_UNSIGNED_INT},
      {"Int64", VTK_LONG_LONG},  {"UInt64", VTK_UNSIGNED_LONG_LONG},
      {"Float32", VTK_FLOAT},    {"Float64", VTK_DOUBLE}};
  for (const auto& [name, id] : types)
    if (type != nullptr && std::strcmp(type, name) == 0) return id;
  return 0;
}

template <typename T>
void widen(const std::vector<unsigned char>& bytes, std::size_t count, std::vector<double>& out) {
  for (std::size_t i = 0; i < count; ++i) {
    T value;
    std::memcpy(&value, bytes.data() + i * sizeof(T), sizeof(T));
    out[i] = static_cast<double>(value);
  }
}

/// `count` values of a numeric DataArray, as doubles (exact for every integer a mesh file can
/// hold and for both float types), read by VTK's parser: ASCII, inline base64 or appended, with
/// the file's compressor, whose headers check_element has bounded.
std::vector<double> read_values(const std::filesystem::path& path, ParsedFile& parsed,
                                vtkXMLDataElement& element, std::size_t count, const std::string& what) {
  const char* type = element.GetAttribute("type");
  const int word = word_type(type);
  if (word == 0)
    throw_file_error(path, what + ": expected a numeric type (Int8 to UInt64, Float32 or Float64), found " +
                               (type ? "'" + std::string(type) + "'" : std::string("none")));
  const std::size_t word_size = parsed.parser->GetWordTypeSize(word);
  std::vector<unsigned char> bytes(count * word_size);
  const char* format = element.GetAttribute("format");
  std::size_t read = 0;
  if (count > 0) {
    if (std::strcmp(format, "appended") == 0) {
      long long offset = 0;
      if (!element.GetScalarAttribute("offset", offset) || offset < 0)
        throw_file_error(path, what + ": expected an offset into the appended data, found none");
      read = parsed.parser->ReadAppendedData(offset, bytes.data(), 0, count, word);
    } else {
      read = parsed.parser->ReadInlineData(&element, std::strcmp(format, "ascii") == 0, bytes.data(), 0,
                                           count, word);
    }
  }
  if (read != count)
    throw_file_error(path,
                     what + ": expected " + std::to_string(count) + " values, found " + std::to_string(read));
  std::vector<double> values(count);
  switch (word) {
  case VTK_SIGNED_CHAR: widen<signed char>(bytes, count, values); break;
  case VTK_UNSIGNED_CHAR: widen<unsigned char>(bytes, count, values); break;
  case VTK_SHORT: widen<std::int16_t>(bytes, count, values); break;
  case VTK_UNSIGNED_SHORT: widen<std::uint16_t>(bytes, count, values); break;
  case VTK_INT: widen<std::int32_t>(bytes, count, values); break;
  case VTK_UNSIGNED_INT: widen<std::uint32_t>(bytes, count, values); break;
  case VTK_LONG_LONG: widen<std::int64_t>(bytes, count, values); break;
  case VTK_UNSIGNED_LONG_LONG: widen<std::uint64_t>(bytes, count, values); break;
  case VTK_FLOAT: widen<float>(bytes, count, values); break;
  default: widen<double>(bytes, count, values); break;
  }
  return values;
}

/// A count attribute checked_element has bounded by the file.
std::size_t count_attribute(vtkXMLDataElement& element, const char* name) {
  long long count = 0;
  element.GetScalarAttribute(name, count);
  return static_cast<std::size_t>(std::max(count, 0LL));
}

vtkSmartPointer<vtkDataCompressor> compressor(const std::filesystem::path& path, const char* name) {
  if (name == nullptr) return nullptr;
  if (std::strcmp(name, "vtkZLibDataCompressor") == 0) return vtkSmartPointer<vtkZLibDataCompressor>::New();
  if (std::strcmp(name, "vtkLZ4DataCompressor") == 0) return vtkSmartPointer<vtkLZ4DataCompressor>::New();
  if (std::strcmp(name, "vtkLZMADataCompressor") == 0) return vtkSmartPointer<vtkLZMADataCompressor>::New();
  throw_file_error(path,
                   std::string("expected the compressor vtkZLibDataCompressor, vtkLZ4DataCompressor or ") +
                       "vtkLZMADataCompressor, found '" + name + "'");
}

} // namespace

void check_vtk_xml_sizes(const std::filesystem::path& path) {
  make_vtk_ready();
  ParsedFile parsed;
  parse(path, parsed);
  if (parsed.root != nullptr) check_element(path, parsed.file, *parsed.root, parsed.layout);
}

namespace {

/// What a .vtp or .vtu file's pieces hold: points, cells as vertex indices into all points, and
/// (for an unstructured grid) each cell's VTK type.
struct PieceCells {
  std::vector<double> points;
  std::vector<std::vector<long long>> cells;
  std::vector<int> types;
  std::vector<VtuCellArray> cell_arrays;
};

/// The names one kind of VTK XML file gives its parts: PolyData with Polys, UnstructuredGrid
/// with Cells (and their types).
struct CellLayout {
  const char* type;    ///< the root's type and the dataset element: PolyData, UnstructuredGrid
  const char* count;   ///< the piece's cell count attribute: NumberOfPolys, NumberOfCells
  const char* element; ///< the element holding offsets and connectivity: Polys, Cells
  const char* noun;    ///< a cell in messages: polygon, cell
  bool types;          ///< whether each cell has a VTK type (a "types" array)
  bool cell_arrays;    ///< whether to read the numeric arrays of the cell data
};

/// The numeric arrays of a piece's CellData (`cell_count` cells) into `arrays`, each appended to
/// the one of its name; on the first piece with cells they are created. `pieces` counts, per
/// array, the pieces that held it.
void read_cell_arrays(const std::filesystem::path& path, ParsedFile& parsed, vtkXMLDataElement& piece,
                      std::size_t cell_count, std::uint64_t most, bool first, const std::string& where,
                      std::vector<VtuCellArray>& arrays, std::vector<int>& pieces) {
  vtkXMLDataElement* data = child(piece, "CellData");
  if (data == nullptr) return;
  for (int i = 0; i < data->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement& element = *data->GetNestedElement(i);
    if (element.GetName() == nullptr || std::strcmp(element.GetName(), "DataArray") != 0) continue;
    if (word_type(element.GetAttribute("type")) == 0) continue; // a string array
    const char* name = element.GetAttribute("Name");
    const std::string array_name = name ? name : "";
    long long components = 1;
    element.GetScalarAttribute("NumberOfComponents", components);
    const std::string what = where + " cell array '" + array_name + "'";
    // As the offsets: no more values than the file's bytes can hold.
    if (components < 1 ||
        static_cast<std::uint64_t>(components) > most / std::max<std::size_t>(cell_count, 1))
      throw_file_error(path, what + ": expected 1 to " +
                                 std::to_string(most / std::max<std::size_t>(cell_count, 1)) +
                                 " components, found " + std::to_string(components));
    auto found = std::find_if(arrays.begin(), arrays.end(),
                              [&](const VtuCellArray& a) { return a.name == array_name; });
    if (found == arrays.end()) {
      if (!first) continue; // not in an earlier piece: dropped at the end anyway
      arrays.push_back({array_name, static_cast<int>(components), {}});
      pieces.push_back(0);
      found = arrays.end() - 1;
    }
    const auto index = static_cast<std::size_t>(found - arrays.begin());
    if (found->components != components || pieces[index] < 0) {
      pieces[index] = -1; // components that differ between pieces: dropped
      continue;
    }
    const std::vector<double> values =
        read_values(path, parsed, element, cell_count * static_cast<std::size_t>(components), what);
    found->values.insert(found->values.end(), values.begin(), values.end());
    ++pieces[index];
  }
}

PieceCells read_piece_cells(const std::filesystem::path& path, const CellLayout& layout) {
  ParsedFile parsed;
  parse(path, parsed);
  if (parsed.root == nullptr)
    throw_file_error(path, "expected a VTK XML file, found one VTK's XML parser cannot read");
  vtkXMLDataElement& root = *parsed.root;
  const char* type = root.GetAttribute("type");
  if (type == nullptr || std::strcmp(type, layout.type) != 0)
    throw_file_error(path, std::string("expected a VTK XML file of type ") + layout.type + ", found type " +
                               (type ? "'" + std::string(type) + "'" : std::string("none")));
  check_element(path, parsed.file, root, parsed.layout);
  parsed.parser->SetCompressor(compressor(path, root.GetAttribute("compressor")));
  vtkXMLDataElement* dataset = child(root, layout.type);
  if (dataset == nullptr)
    throw_file_error(path, std::string("expected a ") + layout.type + " element, found none");
  const std::string noun = layout.noun;

  PieceCells out;
  int piece_index = 0;
  int pieces_with_cells = 0;
  std::vector<int> pieces_of_array; // per cell array: the pieces holding it, -1 when dropped
  for (int i = 0; i < dataset->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement& piece = *dataset->GetNestedElement(i);
    if (piece.GetName() == nullptr || std::strcmp(piece.GetName(), "Piece") != 0) continue;
    const std::string where = "piece " + std::to_string(piece_index++);
    const std::size_t point_count = count_attribute(piece, "NumberOfPoints");
    const std::size_t cell_count = count_attribute(piece, layout.count);
    const std::size_t first_point = out.points.size() / 3;
    if (point_count > 0) {
      vtkXMLDataElement* points = child(piece, "Points");
      vtkXMLDataElement* array = points ? data_array(*points, nullptr) : nullptr;
      if (array == nullptr) throw_file_error(path, where + ": expected the points' DataArray, found none");
      long long components = 0;
      if (!array->GetScalarAttribute("NumberOfComponents", components) || components != 3)
        throw_file_error(path,
                         where + ": expected points of 3 components, found " + std::to_string(components));
      const std::vector<double> xyz = read_values(path, parsed, *array, 3 * point_count, where + " points");
      out.points.insert(out.points.end(), xyz.begin(), xyz.end());
    }
    if (cell_count == 0) continue;
    vtkXMLDataElement* block = child(piece, layout.element);
    vtkXMLDataElement* offsets_array = block ? data_array(*block, "offsets") : nullptr;
    vtkXMLDataElement* connectivity_array = block ? data_array(*block, "connectivity") : nullptr;
    if (offsets_array == nullptr || connectivity_array == nullptr)
      throw_file_error(
          path, where + ": expected the " + noun + "s' offsets and connectivity, found " +
                    (block ? std::string("not both") : "no " + std::string(layout.element) + " element"));
    const std::vector<double> offsets =
        read_values(path, parsed, *offsets_array, cell_count, where + " " + noun + " offsets");
    // Offsets end each cell in the connectivity: they never fall, and the last is its length, which
    // the file must hold (a value takes at least a byte of ASCII, or expands a compressed byte
    // at most k_max_expansion times).
    const std::uint64_t most = parsed.layout.compressed
                                   ? k_max_expansion * parsed.layout.file_size + k_block_slack
                                   : parsed.layout.file_size;
    double previous = 0.0;
    for (std::size_t c = 0; c < cell_count; ++c) {
      if (!(offsets[c] >= previous) || offsets[c] > static_cast<double>(most) ||
          offsets[c] != std::floor(offsets[c]))
        throw_file_error(path, where + " " + noun + " " + std::to_string(c) +
                                   ": expected a whole offset from " +
                                   std::to_string(static_cast<long long>(previous)) + " and at most " +
                                   std::to_string(most) + ", found " + format_number(offsets[c]));
      previous = offsets[c];
    }
    const std::vector<double> connectivity =
        read_values(path, parsed, *connectivity_array, static_cast<std::size_t>(previous),
                    where + " " + noun + " connectivity");
    std::size_t begin = 0;
    for (std::size_t c = 0; c < cell_count; ++c) {
      const auto end = static_cast<std::size_t>(offsets[c]);
      std::vector<long long> cell;
      for (std::size_t k = begin; k < end; ++k) {
        const double id = connectivity[k];
        if (!(id >= 0.0 && id < static_cast<double>(point_count)) || id != std::floor(id))
          throw_file_error(path, where + " " + noun + " " + std::to_string(c) +
                                     ": expected vertex indices that refer to the piece's " +
                                     std::to_string(point_count) + " points, found " + format_number(id));
        cell.push_back(static_cast<long long>(first_point) + static_cast<long long>(id));
      }
      out.cells.push_back(std::move(cell));
      begin = end;
    }
    if (layout.types) {
      vtkXMLDataElement* types_array = data_array(*block, "types");
      if (types_array == nullptr) throw_file_error(path, where + ": expected the cells' types, found none");
      for (const double t : read_values(path, parsed, *types_array, cell_count, where + " cell types")) {
        if (!(t >= 0.0 && t <= 255.0) || t != std::floor(t))
          throw_file_error(path,
                           where + ": expected VTK cell types from 0 to 255, found " + format_number(t));
        out.types.push_back(static_cast<int>(t));
      }
    }
    if (layout.cell_arrays)
      read_cell_arrays(path, parsed, piece, cell_count, most, pieces_with_cells == 0, where, out.cell_arrays,
                       pieces_of_array);
    ++pieces_with_cells;
  }
  // An array some piece with cells lacks has no value for its cells: left out.
  std::vector<VtuCellArray> complete;
  for (std::size_t a = 0; a < out.cell_arrays.size(); ++a)
    if (pieces_of_array[a] == pieces_with_cells) complete.push_back(std::move(out.cell_arrays[a]));
  out.cell_arrays = std::move(complete);
  return out;
}

} // namespace

VtpPolygons read_vtp_polygons(const std::filesystem::path& path) {
  make_vtk_ready();
  PieceCells read = read_piece_cells(path, {"PolyData", "NumberOfPolys", "Polys", "polygon", false, false});
  return {std::move(read.points), std::move(read.cells)};
}

VtuCells read_vtu_cells(const std::filesystem::path& path, bool with_cell_arrays) {
  make_vtk_ready();
  PieceCells read =
      read_piece_cells(path, {"UnstructuredGrid", "NumberOfCells", "Cells", "cell", true, with_cell_arrays});
  return {std::move(read.points), std::move(read.cells), std::move(read.types), std::move(read.cell_arrays)};
}

} // namespace phantasm
