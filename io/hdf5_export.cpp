#include "io/hdf5_export.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "io/dataset_layout.hpp"
#include "io/nifti_file.hpp"

#include <hdf5.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace phantasm {
namespace {

std::string read_text(const std::filesystem::path& path) {
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
  Handle(hid_t id, herr_t (*close)(hid_t)) : m_id(id), m_close(close) {}
  ~Handle() {
    if (m_id >= 0) m_close(m_id);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return m_id; }

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
/// (component-major for vectors, as NIfTI stores them).
template <class T>
void write_array(hid_t file, const std::string& path, const ImageGrid& grid,
                 const std::vector<double>& values, int components, hid_t memory_type,
                 const Hdf5ExportOptions& options, const std::map<std::string, std::string>& attributes) {
  const auto nx = static_cast<std::size_t>(grid.dims.x()), ny = static_cast<std::size_t>(grid.dims.y()),
             nz = static_cast<std::size_t>(grid.dims.z());
  const std::size_t count = nx * ny * nz, nc = static_cast<std::size_t>(components);
  std::vector<T> data(count * nc);
  for (std::size_t c = 0; c < nc; ++c)
    for (std::size_t z = 0; z < nz; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x)
          data[((x * ny + y) * nz + z) * nc + c] = static_cast<T>(values[c * count + (z * ny + y) * nx + x]);
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
  check(H5Dwrite(dataset.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), "write " + path);
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

} // namespace

Hdf5ExportSummary export_hdf5(const std::filesystem::path& dataset, const std::filesystem::path& file,
                              const Hdf5ExportOptions& options,
                              const std::function<void(const std::string&)>& progress) {
  const std::filesystem::path derivatives = dataset / "derivatives" / "phantasm";
  std::vector<std::string> subjects;
  for (const std::string& id : complete_subjects(dataset))
    subjects.push_back("sub-" + id);
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
    const Handle h5(check_id(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                             "create " + temporary.string()),
                    H5Fclose);
    const Handle root(check_id(H5Gopen2(h5.get(), "/", H5P_DEFAULT), "open /"), H5Gclose);
    string_attribute(root.get(), "format", "phantasm HDF5 export 1");
    string_attribute(root.get(), "generated_by", std::string("phantasm ") + version);
    string_attribute(root.get(), "label_table", read_text(derivatives / "dseg.tsv"));
    string_attribute(root.get(), "dataset_description", read_text(dataset / "dataset_description.json"));
    string_attribute(
        root.get(), "conventions",
        "arrays are indexed (i, j, k[, component]) like nibabel's get_fdata(); 'affine' maps (i, j, k, "
        "1) to RAS mm; fields are ITK/elastix displacement fields, components in LPS mm, x_moving = "
        "x_fixed + u(x_fixed)");
    const auto participants = read_participants(dataset / "participants.tsv");
    static const std::regex image(
        R"(sub-[A-Za-z0-9]+/ses-(ref|def)/anat/sub-[A-Za-z0-9]+_ses-(ref|def)_([A-Za-z0-9]+)\.nii\.gz)");
    static const std::regex labels(
        R"(derivatives/phantasm/sub-[A-Za-z0-9]+/ses-(ref|def)/anat/.*_dseg\.nii\.gz)");
    static const std::regex field(
        R"(derivatives/phantasm/sub-[A-Za-z0-9]+/xfm/sub-[A-Za-z0-9]+_(from-[a-z]+_to-[a-z]+)_mode-image_xfm\.nii\.gz)");
    static const std::regex mask(
        R"(derivatives/phantasm/sub-[A-Za-z0-9]+/xfm/sub-[A-Za-z0-9]+_(from-[a-z]+_to-[a-z]+)_desc-exact_mask\.nii\.gz)");
    static const std::regex jacobian(R"(derivatives/phantasm/sub-[A-Za-z0-9]+/xfm/.*_jacobian\.nii\.gz)");
    for (const std::string& subject : subjects) {
      const std::string provenance_text = read_text(derivatives / subject / "provenance.json");
      nlohmann::json provenance;
      try {
        provenance = nlohmann::json::parse(provenance_text);
      } catch (const nlohmann::json::exception& error) {
        throw InputError((derivatives / subject / "provenance.json").string() +
                         ": expected the JSON phantasm writes, found a file it cannot parse (" +
                         error.what() + ")");
      }
      {
        const Handle group(group_at(h5.get(), "/" + subject), H5Gclose);
        string_attribute(group.get(), "provenance", provenance_text);
        const auto row = participants.find(subject);
        if (row != participants.end()) {
          for (const auto& [key, value] : row->second)
            string_attribute(group.get(), key, value);
        }
      }
      for (const auto& entry : provenance.at("files")) {
        throw_if_cancelled(); // the temporary file is removed below
        const std::string relative = entry.get<std::string>();
        const std::filesystem::path path = dataset / relative;
        std::smatch m;
        std::map<std::string, std::string> attributes{{"source", relative}};
        const std::filesystem::path sidecar = sidecar_path(path);
        if (std::filesystem::exists(sidecar)) attributes["sidecar"] = read_text(sidecar);
        if (std::regex_match(relative, m, image)) {
          const NiftiVolume volume = read_nifti(path);
          write_array<float>(h5.get(), "/" + subject + "/ses-" + m[1].str() + "/" + m[3].str(), volume.grid,
                             volume.values, 1, H5T_NATIVE_FLOAT, options, attributes);
        } else if (std::regex_match(relative, m, labels)) {
          const NiftiVolume volume = read_nifti(path);
          write_array<std::int32_t>(h5.get(), "/" + subject + "/ses-" + m[1].str() + "/dseg", volume.grid,
                                    volume.values, 1, H5T_NATIVE_INT32, options, attributes);
        } else if (std::regex_match(relative, m, field)) {
          const NiftiVolume volume = read_nifti_vectors(path, 3);
          write_array<float>(h5.get(), "/" + subject + "/xfm/" + m[1].str(), volume.grid, volume.values, 3,
                             H5T_NATIVE_FLOAT, options, attributes);
        } else if (std::regex_match(relative, m, mask)) {
          const NiftiVolume volume = read_nifti(path);
          write_array<std::uint8_t>(h5.get(), "/" + subject + "/xfm/" + m[1].str() + "_exact_mask",
                                    volume.grid, volume.values, 1, H5T_NATIVE_UINT8, options, attributes);
        } else if (std::regex_match(relative, m, jacobian)) {
          const NiftiVolume volume = read_nifti(path);
          write_array<float>(h5.get(), "/" + subject + "/xfm/jacobian", volume.grid, volume.values, 1,
                             H5T_NATIVE_FLOAT, options, attributes);
        } else {
          continue;
        }
        ++summary.arrays;
      }
      ++summary.subjects;
      if (progress) progress(subject);
    }
    check(H5Fflush(h5.get(), H5F_SCOPE_GLOBAL), "flush " + temporary.string());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
  std::filesystem::rename(temporary, file);
  return summary;
}

} // namespace phantasm
