#include "atlas/atlas_labels.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/sha256.hpp"

#include <fstream>
#include <iterator>
#include <sstream>

namespace phantasm {
namespace {

std::string file_sha256(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return sha256_hex(bytes);
}

/// The volume with `margin` background voxels added on every side; voxel (i, j, k) of the input
/// is voxel (i + margin, ...) of the result, at the same world position.
HeadLabels padded(const HeadLabels& head, int margin) {
  HeadLabels out;
  out.table = head.table;
  out.grid = head.grid;
  out.grid.dims = head.grid.dims + Eigen::Vector3i::Constant(2 * margin);
  out.grid.world_from_voxel.topRightCorner<3, 1>() =
      head.grid.world_from_index(Eigen::Vector3d::Constant(-margin));
  out.labels.assign(static_cast<std::size_t>(out.grid.voxel_count()), 0);
  const Eigen::Vector3i& d = head.grid.dims;
  for (int k = 0; k < d.z(); ++k)
    for (int j = 0; j < d.y(); ++j)
      for (int i = 0; i < d.x(); ++i)
        out.labels[voxel_index(out.grid.dims, i + margin, j + margin, k + margin)] =
            head.labels[voxel_index(d, i, j, k)];
  return out;
}

} // namespace

std::vector<std::string> atlas_names() {
  return {"colin27"};
}

std::vector<std::filesystem::path> atlas_input_files(const std::string& atlas,
                                                     const std::filesystem::path& templates_dir) {
  if (atlas != "colin27") throw InputError("atlas: expected one of colin27, found '" + atlas + "'");
  return {templates_dir / "ch2.nii.gz", templates_dir / "ch2bet.nii.gz", templates_dir / "aal.nii.gz"};
}

AtlasLabels derive_atlas_labels(const std::string& atlas, const std::filesystem::path& templates_dir) {
  const std::vector<std::filesystem::path> inputs = atlas_input_files(atlas, templates_dir);
  AtlasLabels result;
  result.head = padded(derive_colin27_head(templates_dir), 2);
  result.source = "atlas colin27 (" + templates_dir.string() + ")";
  for (const std::filesystem::path& input : inputs)
    result.provenance.push_back("colin27 input " + input.string() + " sha256 " + file_sha256(input));
  const auto& labels = result.head.labels;
  const std::string bytes(reinterpret_cast<const char*>(labels.data()), labels.size() * sizeof(labels[0]));
  const Eigen::Vector3i& dims = result.head.grid.dims;
  std::ostringstream derived;
  // No time here: the log and provenance.json hold the same bytes on every run (the anatomy
  // stage's time is in its stage report).
  derived << "colin27 labels derived (docs/anatomy-colin27.md): " << dims.x() << " x " << dims.y() << " x "
          << dims.z() << " voxels of " << format_number(result.head.grid.spacing_mm.x())
          << " mm (the template's grid padded by 2 "
          << "voxels), int32 labels sha256 " << sha256_hex(bytes);
  result.provenance.push_back(derived.str());
  result.provenance.push_back(
      "colin27 sources: Holmes CJ et al. Enhancement of MR images using registration for signal averaging. "
      "J Comput Assist Tomogr 1998; 22:324-333 (Colin 27); Tzourio-Mazoyer N et al. Automated anatomical "
      "labeling of activations in SPM using a macroscopic anatomical parcellation of the MNI MRI "
      "single-subject brain. NeuroImage 2002; 15:273-289 (AAL)");
  return result;
}

} // namespace phantasm
