#include "atlas/atlas_regions.hpp"

#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/nifti_file.hpp"

#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

const char* const aal_package = "mricron-data";

std::filesystem::path require_file(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError("atlas aal: " + path.string() + " not found; it comes with the Debian package " +
                     std::string(aal_package) + " (apt-get install " + aal_package + ")");
  }
  return path;
}

std::string sha256_of_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return sha256_hex(std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
}

/// The names file: one "label name code" line per region.
std::map<std::string, std::int32_t> read_region_names(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::map<std::string, std::int32_t> regions;
  std::string line;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream fields(line);
    long label = 0;
    std::string name;
    if (!(fields >> label >> name) || label <= 0 || label > 65535) {
      throw InputError(path.string() + ":" + std::to_string(line_number) +
                       ": expected 'label name code' with a label in [1, 65535], found '" + line + "'");
    }
    regions[name] = static_cast<std::int32_t>(label);
  }
  if (regions.empty()) throw InputError(path.string() + ": expected region names, found none");
  return regions;
}

/// Bilateral pairs by their name without the side, and the cerebral cortex.
std::map<std::string, std::vector<std::string>>
aal_groups(const std::map<std::string, std::int32_t>& regions) {
  std::map<std::string, std::vector<std::string>> groups;
  for (const auto& [name, label] : regions) {
    if (name.size() < 3 || name.compare(name.size() - 2, 2, "_L") != 0) continue;
    const std::string base = name.substr(0, name.size() - 2);
    if (regions.count(base + "_R") != 0 && regions.count(base) == 0) groups[base] = {name, base + "_R"};
  }
  const std::set<std::string> not_cortex = {"Hippocampus", "Amygdala", "Caudate",
                                            "Putamen",     "Pallidum", "Thalamus"};
  std::vector<std::string>& cortex = groups["cortex"];
  for (const auto& [name, label] : regions) {
    const std::string base = name.size() > 2 ? name.substr(0, name.size() - 2) : name;
    if (label >= 1 && label <= 90 && not_cortex.count(base) == 0) cortex.push_back(name);
  }
  return groups;
}

} // namespace

std::vector<std::string> region_atlas_names() {
  return {"aal"};
}

AtlasRegions read_atlas_regions(const std::string& atlas, const std::filesystem::path& templates_dir) {
  if (atlas != "aal") throw InputError("atlas: expected one of aal, found '" + atlas + "'");
  const std::filesystem::path image = require_file(templates_dir / "aal.nii.gz");
  const std::filesystem::path names = require_file(templates_dir / "aal.nii.txt");
  const NiftiVolume volume = read_nifti(image);
  AtlasRegions result;
  result.grid = volume.grid;
  result.labels.resize(volume.values.size());
  for (std::size_t n = 0; n < volume.values.size(); ++n)
    result.labels[n] = static_cast<std::int32_t>(std::lround(volume.values[n]));
  result.regions = read_region_names(names);
  result.groups = aal_groups(result.regions);
  result.source = "atlas aal (" + image.string() + ", " + names.string() + ")";
  for (const auto& path : {image, names})
    result.provenance.push_back("aal input " + path.string() + " sha256 " + sha256_of_file(path));
  result.provenance.push_back(
      "aal source: Tzourio-Mazoyer N et al. Automated anatomical labeling of activations in SPM using a "
      "macroscopic anatomical parcellation of the MNI MRI single-subject brain. NeuroImage 2002; 15:273-289");
  return result;
}

} // namespace phantasm
