#include "io/hdf5_export.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/path_kind.hpp"
#include "core/version.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"

#include <hdf5.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace phantasm {
namespace {

/// A file of the dataset as text; "" when there is none (a sidecar or participants.tsv may be
/// missing). A folder or a device in its place is an error: reading one threw the library's
/// "basic_filebuf::underflow error reading the file: Is a directory".
std::string read_text(const std::filesystem::path& path) {
  const std::string kind = path_kind(path);
  if (kind == "no such file") return {};
  if (kind != "a regular file")
    throw InputError(path.string() + ": expected a file phantasm writes, found " + kind);
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: cannot " + what);
}

hid_t check_id(hid_t id, const std::string& what) {
  if (id < 0) throw std::runtime_error("HDF5: cannot " + what);
  return id;
}

/// An HDF5 handle closed by its destructor.
class Handle {
public:
  Handle(hid_t id, herr_t (*closer)(hid_t)) : m_id(id), m_close(closer) {}
  ~Handle() {
    if (m_id >= 0) m_close(m_id);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return m_id; }
  /// Closes now and returns HDF5's status (a file's close writes what it still holds).
  herr_t close() {
    const herr_t status = m_id >= 0 ? m_close(m_id) : 0;
    m_id = -1;
    return status;
  }

private:
  hid_t m_id;
  herr_t (*m_close)(hid_t);
};

void string_attribute(hid_t object, const std::string& name, const std::string& value) {
  const Handle type(check_id(H5Tcopy(H5T_C_S1), "make a string type"), H5Tclose);
  check(H5Tset_size(type.get(), H5T_VARIABLE), "size a string type");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "set UTF-8");
  const Handle space(check_id(H5Screate(H5S_SCALAR), "make a scalar space"), H5Sclose);
  const Handle attribute(
      check_id(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
               "create attribute " + name),
      H5Aclose);
  const char* text = value.c_str();
  check(H5Awrite(attribute.get(), type.get(), &text), "write attribute " + name);
}

void affine_attribute(hid_t object, const ImageGrid& grid) {
  double affine[16];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      affine[4 * r + c] = grid.world_from_voxel(r, c);
  const hsize_t dims[2] = {4, 4};
  const Handle space(check_id(H5Screate_simple(2, dims, nullptr), "make a 4x4 space"), H5Sclose);
  const Handle attribute(
      check_id(H5Acreate2(object, "affine", H5T_NATIVE_DOUBLE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
               "create affine"),
      H5Aclose);
  check(H5Awrite(attribute.get(), H5T_NATIVE_DOUBLE, affine), "write affine");
}

/// Opens or creates the group at a slash-separated path.
hid_t group_at(hid_t file, const std::string& path) {
  std::string current;
  std::stringstream parts(path);
  std::string part;
  hid_t group = -1;
  while (std::getline(parts, part, '/')) {
    if (part.empty()) continue;
    current += "/" + part;
    if (group >= 0) H5Gclose(group);
    group = H5Lexists(file, current.c_str(), H5P_DEFAULT) > 0
                ? H5Gopen2(file, current.c_str(), H5P_DEFAULT)
                : H5Gcreate2(file, current.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    check_id(group, "open group " + current);
  }
  return group;
}

/// Writes a chunked, compressed array of (i, j, k[, component]) from values stored with i fastest
/// (component-major for vectors, as NIfTI stores them). Written in blocks of whole chunks (one
/// chunk edge along i and j, the whole k axis), with a cancellation poll between blocks: one
/// H5Dwrite of a large array compresses for seconds without a chance to stop, and needed a
/// transposed copy of the whole array besides.
template <class T>
void write_array(hid_t file, const std::string& path, const ImageGrid& grid,
                 const std::vector<double>& values, int components, hid_t memory_type,
                 const Hdf5ExportOptions& options, const std::map<std::string, std::string>& attributes) {
  const auto nx = static_cast<std::size_t>(grid.dims.x()), ny = static_cast<std::size_t>(grid.dims.y()),
             nz = static_cast<std::size_t>(grid.dims.z());
  const std::size_t count = nx * ny * nz, nc = static_cast<std::size_t>(components);
  const int rank = components > 1 ? 4 : 3;
  const hsize_t dims[4] = {nx, ny, nz, nc};
  const hsize_t edge = static_cast<hsize_t>(std::max(1, options.chunk));
  const hsize_t chunks[4] = {std::min<hsize_t>(edge, nx), std::min<hsize_t>(edge, ny),
                             std::min<hsize_t>(edge, nz), nc};
  const Handle space(check_id(H5Screate_simple(rank, dims, nullptr), "make a space for " + path), H5Sclose);
  const Handle properties(check_id(H5Pcreate(H5P_DATASET_CREATE), "make dataset properties"), H5Pclose);
  check(H5Pset_chunk(properties.get(), rank, chunks), "chunk " + path);
  check(H5Pset_shuffle(properties.get()), "shuffle " + path);
  check(H5Pset_deflate(properties.get(), static_cast<unsigned>(std::clamp(options.compression, 0, 9))),
        "compress " + path);
  const std::size_t slash = path.rfind('/');
  const Handle group(group_at(file, path.substr(0, slash)), H5Gclose);
  const Handle dataset(check_id(H5Dcreate2(group.get(), path.substr(slash + 1).c_str(), memory_type,
                                           space.get(), H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                                "create dataset " + path),
                       H5Dclose);
  const auto bx = static_cast<std::size_t>(chunks[0]), by = static_cast<std::size_t>(chunks[1]);
  std::vector<T> block(bx * by * nz * nc);
  for (std::size_t x0 = 0; x0 < nx; x0 += bx) {
    for (std::size_t y0 = 0; y0 < ny; y0 += by) {
      if (const int delay = write_delay_for_testing(); delay > 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(delay));
      throw_if_cancelled(); // the caller removes the temporary file
      const std::size_t sx = std::min(bx, nx - x0), sy = std::min(by, ny - y0);
      for (std::size_t c = 0; c < nc; ++c)
        for (std::size_t z = 0; z < nz; ++z)
          for (std::size_t y = 0; y < sy; ++y)
            for (std::size_t x = 0; x < sx; ++x)
              block[((x * sy + y) * nz + z) * nc + c] =
                  static_cast<T>(values[c * count + (z * ny + y0 + y) * nx + x0 + x]);
      const hsize_t start[4] = {x0, y0, 0, 0};
      const hsize_t size[4] = {sx, sy, nz, nc};
      check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, size, nullptr),
            "select a block of " + path);
      const Handle memory(check_id(H5Screate_simple(rank, size, nullptr), "make a block space for " + path),
                          H5Sclose);
      check(H5Dwrite(dataset.get(), memory_type, memory.get(), space.get(), H5P_DEFAULT, block.data()),
            "write " + path);
    }
  }
  affine_attribute(dataset.get(), grid);
  for (const auto& [name, value] : attributes)
    string_attribute(dataset.get(), name, value);
}

/// The participants.tsv values of each subject ("sub-01" -> column -> value).
std::map<std::string, std::map<std::string, std::string>>
read_participants(const std::filesystem::path& file) {
  std::map<std::string, std::map<std::string, std::string>> rows;
  std::istringstream text(read_text(file));
  std::string line;
  std::vector<std::string> header;
  while (std::getline(text, line)) {
    std::vector<std::string> fields;
    std::stringstream parts(line);
    std::string field;
    while (std::getline(parts, field, '\t'))
      fields.push_back(field);
    if (header.empty()) {
      header = fields;
      continue;
    }
    for (std::size_t f = 1; f < fields.size() && f < header.size(); ++f)
      rows[fields[0]][header[f]] = fields[f];
  }
  return rows;
}

/// A variable-length UTF-8 string array attribute (names of landmarks, organs).
void strings_attribute(hid_t object, const std::string& name, const std::vector<std::string>& values) {
  const Handle type(check_id(H5Tcopy(H5T_C_S1), "make a string type"), H5Tclose);
  check(H5Tset_size(type.get(), H5T_VARIABLE), "size a string type");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "set UTF-8");
  const hsize_t count = values.size();
  const Handle space(check_id(H5Screate_simple(1, &count, nullptr), "make a space for " + name), H5Sclose);
  const Handle attribute(
      check_id(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
               "create attribute " + name),
      H5Aclose);
  std::vector<const char*> texts;
  for (const std::string& value : values)
    texts.push_back(value.c_str());
  check(H5Awrite(attribute.get(), type.get(), texts.data()), "write attribute " + name);
}

/// Writes a landmarks CSV ("name,organ,x_mm,y_mm,z_mm") as a float64 (N, 3) array of RAS mm with
/// the names and organs as string-array attributes.
void write_landmarks(hid_t file, const std::string& path, const std::filesystem::path& csv,
                     const std::map<std::string, std::string>& attributes) {
  std::istringstream text(read_text(csv));
  std::string line;
  std::getline(text, line); // header
  std::vector<std::string> names, organs;
  std::vector<double> positions;
  int number = 1;
  while (std::getline(text, line)) {
    ++number;
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream parts(line);
    std::string field;
    while (std::getline(parts, field, ','))
      fields.push_back(field);
    if (fields.size() != 5) {
      throw InputError(csv.string() + ":" + std::to_string(number) +
                       ": expected name,organ,x_mm,y_mm,z_mm, found '" + line + "'");
    }
    names.push_back(fields[0]);
    organs.push_back(fields[1]);
    for (int c = 2; c < 5; ++c) {
      const std::string& number_text = fields[static_cast<std::size_t>(c)];
      char* end = nullptr;
      errno = 0;
      const double value = std::strtod(number_text.c_str(), &end);
      if (number_text.empty() || *end != '\0' || errno != 0 || !std::isfinite(value)) {
        throw InputError(csv.string() + ":" + std::to_string(number) +
                         ": expected three finite numbers (mm) after the name and organ, found '" + line +
                         "'");
      }
      positions.push_back(value);
    }
  }
  const hsize_t dims[2] = {names.size(), 3};
  const Handle space(check_id(H5Screate_simple(2, dims, nullptr), "make a space for " + path), H5Sclose);
  const std::size_t slash = path.rfind('/');
  const Handle group(group_at(file, path.substr(0, slash)), H5Gclose);
  const Handle dataset(check_id(H5Dcreate2(group.get(), path.substr(slash + 1).c_str(), H5T_NATIVE_DOUBLE,
                                           space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                                "create dataset " + path),
                       H5Dclose);
  if (!positions.empty())
    check(H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, positions.data()),
          "write " + path);
  strings_attribute(dataset.get(), "names", names);
  strings_attribute(dataset.get(), "organs", organs);
  for (const auto& [name, value] : attributes)
    string_attribute(dataset.get(), name, value);
}

/// A path of the dataset layout with one free part (a sequence, tissue or map name): matches a
/// dataset-relative path made by the same layout function and gives the free part back. Built
/// from the layout function itself, so the export follows any change of file names.
class PathPattern {
public:
  /// @param make the layout function, called with a marker in place of the free part
  /// @param bids_suffix the free part is a BIDS suffix (letters and digits only); otherwise an
  /// entity value, which may hold '_' in datasets of earlier versions
  PathPattern(const std::function<std::filesystem::path(const std::string&)>& make,
              const std::filesystem::path& root, bool bids_suffix)
      : m_bids_suffix(bids_suffix) {
    const std::string made = make(k_marker).lexically_relative(root).generic_string();
    const std::size_t at = made.find(k_marker);
    m_prefix = made.substr(0, at);
    m_suffix = made.substr(at + std::string(k_marker).size());
  }
  /// The free part of `relative` when it has this pattern's form (a non-empty part without '/'),
  /// else "".
  std::string match(const std::string& relative) const {
    if (relative.size() <= m_prefix.size() + m_suffix.size() || relative.rfind(m_prefix, 0) != 0 ||
        relative.compare(relative.size() - m_suffix.size(), m_suffix.size(), m_suffix) != 0)
      return {};
    const std::string part =
        relative.substr(m_prefix.size(), relative.size() - m_prefix.size() - m_suffix.size());
    return part.find_first_of(m_bids_suffix ? "/_-" : "/") == std::string::npos ? part : std::string();
  }

private:
  static constexpr const char* k_marker = "phantasmfreepart";
  std::string m_prefix, m_suffix;
  bool m_bids_suffix;
};

/// The "Units" of a JSON sidecar, or `fallback` when it has none.
std::string sidecar_units(const std::string& sidecar, const std::string& fallback) {
  if (sidecar.empty()) return fallback;
  const nlohmann::json json = nlohmann::json::parse(sidecar, nullptr, false);
  if (json.is_object() && json.contains("Units") && json["Units"].is_string()) return json["Units"];
  return fallback;
}

using Participants = std::map<std::string, std::map<std::string, std::string>>;

/// The export's own attributes on the root group: format, version, label table, dataset
/// description and the conventions of its arrays.
void write_root_attributes(hid_t root, const DatasetLayout& any) {
  string_attribute(root, "format", "phantasm HDF5 export 2");
  string_attribute(root, "generated_by", std::string("phantasm ") + version);
  string_attribute(root, "label_table", read_text(any.dseg_table()));
  string_attribute(root, "dataset_description", read_text(any.dataset_description()));
  string_attribute(
      root, "conventions",
      "arrays are indexed (i, j, k[, component]) like nibabel's get_fdata(); 'affine' maps (i, j, k, 1) "
      "to RAS mm; displacement fields are 4-D (X, Y, Z, 3) float32 arrays (the NIfTI file's 5-D "
      "(X, Y, Z, 1, 3) without its singleton axis) of ITK/elastix displacements, components in LPS "
      "mm, x_moving = x_fixed + u(x_fixed); landmarks are (N, 3) RAS mm; every array has attributes "
      "kind, units, frame, axes (its dimensions, space-separated) and source (its file in the "
      "dataset, whose JSON sidecar is attribute sidecar)");
}

/// The subject's files as its provenance lists them (paths relative to the dataset).
nlohmann::json provenance_files(const DatasetLayout& layout, const nlohmann::json& provenance) {
  const nlohmann::json files =
      provenance.is_object() && provenance.contains("files") ? provenance["files"] : nlohmann::json();
  if (!files.is_array() || !std::all_of(files.begin(), files.end(),
                                        [](const nlohmann::json& entry) { return entry.is_string(); })) {
    const std::string found =
        !provenance.is_object() ? "a JSON " + std::string(provenance.type_name()) + " instead of an object"
        : files.is_null()       ? std::string("no such key")
                                : "a JSON " + std::string(files.type_name()) +
                                (files.is_array() ? " with an entry that is not text" : "");
    throw InputError(layout.provenance().string() +
                     ": files: expected the list of the subject's files (paths relative to the dataset), "
                     "found " +
                     found);
  }
  return files;
}

/// What a file of the subject is in the export: its array's name, kind, units and axes.
struct Target {
  std::string key, kind, units, axes;
  int components = 1;
  bool landmarks = false;
  hid_t type = H5T_NATIVE_FLOAT;
};

/// What each file of a subject is, by the layout that wrote it: the files of fixed names, and
/// the patterns of the files named after a tissue, sequence or map.
struct SubjectTargets {
  std::map<std::string, Target> exact;
  std::vector<std::pair<PathPattern, std::function<Target(const std::string&)>>> patterns;

  std::optional<Target> of(const std::string& relative) const {
    if (const auto found = exact.find(relative); found != exact.end()) return found->second;
    for (const auto& [pattern, make] : patterns) {
      const std::string part = pattern.match(relative);
      if (part.empty()) continue;
      return make(part);
    }
    return std::nullopt;
  }
};

/// The targets of one state's files: labels, landmarks, fractions, images and parameter maps.
void add_state_targets(const std::filesystem::path& dataset, const DatasetLayout& layout,
                       const std::string& subject, PhantomState state, SubjectTargets* targets) {
  const auto relative_of = [&](const std::filesystem::path& path) {
    return path.lexically_relative(dataset).generic_string();
  };
  const std::string scalar_axes = "i j k";
  const std::string session = "/" + subject + "/ses-" + session_label(state) + "/";
  targets->exact[relative_of(layout.dseg(state))] = {
      session + "dseg", "labels", "label", scalar_axes, 1, false, H5T_NATIVE_INT32};
  targets->exact[relative_of(layout.landmarks(state))] = {session + "landmarks", "landmarks", "mm",
                                                          "landmark coordinate", 1,           true};
  targets->exact[relative_of(layout.dense_landmarks(state))] = {
      session + "dense_landmarks", "landmarks", "mm", "landmark coordinate", 1, true};
  targets->patterns.emplace_back(
      PathPattern([&](const std::string& x) { return layout.probseg(state, x); }, dataset, false),
      [session, scalar_axes](const std::string& tissue) {
        return Target{session + "probseg/" + tissue, "fraction", "1 (fraction of the voxel, 0 to 1)",
                      scalar_axes};
      });
  targets->patterns.emplace_back(
      PathPattern([&](const std::string& x) { return layout.anat_image(state, x); }, dataset, true),
      [session, scalar_axes](const std::string& suffix) {
        return Target{session + suffix, "image", "arbitrary (magnitude)", scalar_axes};
      });
  // Last: its form (a suffix next to the labels) would also match the label files above.
  targets->patterns.emplace_back(
      PathPattern([&](const std::string& x) { return layout.parameter_map(state, x); }, dataset, true),
      [session, scalar_axes](const std::string& suffix) {
        return Target{session + "maps/" + suffix, "parameter_map", "", scalar_axes};
      });
}

/// The targets of a subject's files: both states', then the fields, masks and Jacobians both ways.
SubjectTargets subject_targets(const std::filesystem::path& dataset, const DatasetLayout& layout,
                               const std::string& subject) {
  SubjectTargets targets;
  const auto relative_of = [&](const std::filesystem::path& path) {
    return path.lexically_relative(dataset).generic_string();
  };
  const std::string scalar_axes = "i j k";
  for (const PhantomState state : {PhantomState::reference, PhantomState::deformed})
    add_state_targets(dataset, layout, subject, state, &targets);
  // Fields are named as their files are (without the subject), so that the HDF5 name and the
  // dataset's name of a field always agree.
  const auto xfm_key = [&](const std::filesystem::path& path) {
    std::string name = path.filename().string();
    name = name.substr(name.find('_') + 1);
    return "/" + subject + "/xfm/" + name.substr(0, name.find('.'));
  };
  auto& exact = targets.exact;
  for (const auto& [from, to] : {std::pair{PhantomState::reference, PhantomState::deformed},
                                 std::pair{PhantomState::deformed, PhantomState::reference}}) {
    exact[relative_of(layout.transform(from, to))] = {xfm_key(layout.transform(from, to)),
                                                      "displacement_field", "mm", "i j k component", 3};
    exact[relative_of(layout.transform_mask(from, to))] = {
        xfm_key(layout.transform_mask(from, to)),
        "exact_mask",
        "1 where the field is the solved motion, 0 where it is the smooth extension",
        scalar_axes,
        1,
        false,
        H5T_NATIVE_UINT8};
    // One Jacobian per direction, on the field's own (the `to` state's) grid.
    exact[relative_of(layout.jacobian(from, to))] = {xfm_key(layout.jacobian(from, to)), "jacobian",
                                                     "1 (volume ratio det(I + grad u))", scalar_axes};
  }
  return targets;
}

/// The attributes of a file's array: its source, kind, axes, frame, units and sidecar.
std::map<std::string, std::string> array_attributes(const std::string& relative,
                                                    const std::filesystem::path& path, const Target& target) {
  std::map<std::string, std::string> attributes{
      {"source", relative},
      {"kind", target.kind},
      {"axes", target.axes},
      {"frame", target.kind == "displacement_field"
                    ? "LPS (components: world millimetres, RAS with x and y negated); grid: affine, RAS"
                : target.landmarks ? "RAS (world millimetres)"
                                   : "grid: affine, RAS"}};
  const std::filesystem::path sidecar = sidecar_path(path);
  std::string sidecar_text;
  if (std::filesystem::exists(sidecar)) attributes["sidecar"] = sidecar_text = read_text(sidecar);
  attributes["units"] = sidecar_units(sidecar_text, target.units.empty() ? "see sidecar" : target.units);
  if (target.kind == "displacement_field") {
    attributes["convention"] =
        "ITK/elastix displacement field as a 4-D (X, Y, Z, 3) array (the NIfTI file is 5-D, (X, Y, Z, "
        "1, 3), with a singleton time axis); components in LPS mm, x_moving = x_fixed + u(x_fixed)";
  }
  return attributes;
}

/// Writes a file of the dataset as its target's array (or landmark table).
void write_target(hid_t h5, const Target& target, const std::filesystem::path& path,
                  const std::map<std::string, std::string>& attributes, const Hdf5ExportOptions& options) {
  if (target.landmarks) {
    write_landmarks(h5, target.key, path, attributes);
  } else if (target.components > 1) {
    const NiftiVolume volume = read_nifti_vectors(path, target.components);
    write_array<float>(h5, target.key, volume.grid, volume.values, target.components, H5T_NATIVE_FLOAT,
                       options, attributes);
  } else {
    const NiftiVolume volume = read_nifti(path);
    if (target.type == H5T_NATIVE_INT32)
      write_array<std::int32_t>(h5, target.key, volume.grid, volume.values, 1, target.type, options,
                                attributes);
    else if (target.type == H5T_NATIVE_UINT8)
      write_array<std::uint8_t>(h5, target.key, volume.grid, volume.values, 1, target.type, options,
                                attributes);
    else
      write_array<float>(h5, target.key, volume.grid, volume.values, 1, target.type, options, attributes);
  }
}

/// Exports one subject: its group (provenance and participants row) and an array per file of
/// its provenance that the export knows; returns the number of arrays.
std::size_t export_subject(hid_t h5, const std::filesystem::path& dataset, const std::string& id,
                           const Participants& participants, const Hdf5ExportOptions& options) {
  const DatasetLayout layout(dataset, id);
  const std::string subject = "sub-" + id;
  const std::string provenance_text = read_text(layout.provenance());
  const nlohmann::json provenance =
      parse_json_text(provenance_text, layout.provenance(), "the JSON phantasm writes in provenance.json");
  const nlohmann::json files = provenance_files(layout, provenance);
  {
    const Handle group(group_at(h5, "/" + subject), H5Gclose);
    string_attribute(group.get(), "provenance", provenance_text);
    const auto row = participants.find(subject);
    if (row != participants.end()) {
      for (const auto& [key, value] : row->second)
        string_attribute(group.get(), key, value);
    }
  }
  const SubjectTargets targets = subject_targets(dataset, layout, subject);
  std::size_t arrays = 0;
  for (const auto& entry : files) {
    throw_if_cancelled(); // the temporary file is removed by the caller
    const std::string relative = entry.get<std::string>();
    const std::filesystem::path path = dataset / relative;
    const std::optional<Target> target = targets.of(relative);
    if (!target) continue;
    write_target(h5, *target, path, array_attributes(relative, path, *target), options);
    ++arrays;
  }
  return arrays;
}

} // namespace

Hdf5ExportSummary export_hdf5(const std::filesystem::path& dataset, const std::filesystem::path& file,
                              const Hdf5ExportOptions& options,
                              const std::function<void(const std::string&)>& progress) {
  const std::vector<std::string> subjects = complete_subjects(dataset);
  if (subjects.empty()) {
    throw InputError(dataset.string() +
                     ": expected a phantasm dataset with complete subjects (derivatives/phantasm/sub-<id>/"
                     "provenance.json), found none");
  }
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); // errors become exceptions with our messages
  const std::filesystem::path temporary =
      file.parent_path() /
      ("." + file.filename().string() + ".phantasm-tmp-" + std::to_string(::getpid()) + "-0");
  if (!file.parent_path().empty()) std::filesystem::create_directories(file.parent_path());
  Hdf5ExportSummary summary;
  try {
    Handle h5(check_id(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                       "create " + temporary.string()),
              H5Fclose);
    Handle root(check_id(H5Gopen2(h5.get(), "/", H5P_DEFAULT), "open /"), H5Gclose);
    write_root_attributes(root.get(), DatasetLayout(dataset, subjects.front()));
    const Participants participants = read_participants(dataset / "participants.tsv");
    for (const std::string& id : subjects) {
      summary.arrays += export_subject(h5.get(), dataset, id, participants, options);
      ++summary.subjects;
      if (progress) progress("sub-" + id);
    }
    check(H5Fflush(h5.get(), H5F_SCOPE_GLOBAL), "flush " + temporary.string());
    // Every other handle is closed (a file with open objects would only close with them).
    check(root.close(), "close /");
    check(h5.close(), "close " + temporary.string());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
  std::filesystem::rename(temporary, file);
  return summary;
}

} // namespace phantasm
