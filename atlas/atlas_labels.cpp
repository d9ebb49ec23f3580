#include "atlas/atlas_labels.hpp"

#include "atlas/extracranial_tissues.hpp"
#include "atlas/voxel_masks.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/sha256.hpp"
#include "io/nifti_file.hpp"
#include "io/segmentation.hpp"

#include <algorithm>
#include <array>
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

std::vector<std::string> segmentation_head_label_names() {
  return {"outer_csf", "scalp", "subcutaneous_fat", "muscle", "skull", "bone_marrow"};
}

AtlasLabels derive_segmentation_head(const std::filesystem::path& labels_file,
                                     const std::filesystem::path& t1_file, const Colin27Options& options) {
  using namespace voxel_masks;
  const NiftiVolume t1 = read_nifti(t1_file);
  ImageGrid label_grid;
  const std::vector<std::int32_t> segmentation = read_nifti_labels(labels_file, &label_grid);
  check_t1_covers_labels(labels_file, label_grid, segmentation, t1_file, t1.grid);
  const ImageGrid& grid = t1.grid;
  const std::size_t count = static_cast<std::size_t>(grid.voxel_count());
  const std::vector<double> resampled =
      resample_nearest(label_grid, std::vector<double>(segmentation.begin(), segmentation.end()), grid);
  std::int32_t largest = 0;
  for (const std::int32_t l : segmentation)
    largest = std::max(largest, l);

  // The brain: every labelled voxel, holes filled. Its white matter: the T1's brightest class
  // there (three classes, majority filtered), as the Colin head's.
  Mask brain(count);
  for (std::size_t n = 0; n < count; ++n)
    brain[n] = resampled[n] != 0.0;
  brain = fill_holes(brain, grid);
  const std::vector<int> levels = t1_levels(t1.values);
  std::array<std::int64_t, 256> histogram{};
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n]) ++histogram[levels[n]];
  const std::array<double, 2> cut = three_class_thresholds(histogram);
  std::vector<std::int8_t> cls(count, 0);
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n]) cls[n] = static_cast<std::int8_t>(levels[n] < cut[0] ? 1 : (levels[n] < cut[1] ? 2 : 3));
  for (int pass = 0; pass < options.majority_filter_passes; ++pass)
    cls = majority_filter(cls, brain, grid);
  Mask white_matter(count);
  for (std::size_t n = 0; n < count; ++n)
    white_matter[n] = cls[n] == 3;
  const ExtracranialTissues outside = derive_extracranial_tissues(grid, levels, brain, white_matter, options);

  // The volume's labels keep their numbers; the derived ones follow its largest.
  const std::vector<std::string> names = segmentation_head_label_names();
  const std::array<const char*, 6> tissues = {
      "csf", "skin", "fat_subcutaneous", "muscle_skeletal", "bone_cortical", "bone_marrow"};
  const std::array<std::int32_t, 6> from = {colin27_csf,    colin27_scalp, colin27_subcutaneous_fat,
                                            colin27_muscle, colin27_skull, colin27_bone_marrow};
  HeadLabels head;
  head.grid = grid;
  head.labels.assign(count, 0);
  for (std::size_t n = 0; n < count; ++n) {
    if (brain[n]) {
      head.labels[n] = resampled[n] != 0.0 ? static_cast<std::int32_t>(resampled[n]) : largest + 1;
      continue;
    }
    for (std::size_t d = 0; d < from.size(); ++d)
      if (outside.labels[n] == from[d]) head.labels[n] = largest + 1 + static_cast<std::int32_t>(d);
  }
  head.table.push_back({0, "background", ""});
  for (std::size_t d = 0; d < names.size(); ++d)
    head.table.push_back({largest + 1 + static_cast<std::int32_t>(d), names[d], tissues[d]});

  AtlasLabels result;
  result.head = padded(head, 2);
  result.source = "segmentation " + labels_file.string() + " with T1 " + t1_file.string();
  for (const std::filesystem::path& input : {labels_file, t1_file})
    result.provenance.push_back("segmentation head input " + input.string() + " sha256 " +
                                file_sha256(input));
  const auto& labels = result.head.labels;
  const std::string bytes(reinterpret_cast<const char*>(labels.data()), labels.size() * sizeof(labels[0]));
  const Eigen::Vector3i& dims = result.head.grid.dims;
  std::ostringstream derived;
  derived << "segmentation head derived: the labels of " << labels_file.string() << " on the grid of the T1 "
          << t1_file.string() << " (" << dims.x() << " x " << dims.y() << " x " << dims.z() << " voxels of "
          << format_number(grid.spacing_mm.x()) << " mm, padded by 2 voxels) with the tissues outside the "
          << "brain derived from the T1 by the Colin 27 head's method (docs/anatomy-colin27.md, Method: head "
          << "threshold " << outside.head_threshold << ", white-matter mean "
          << format_number(outside.white_matter_mean) << "), labels ";
  for (std::size_t d = 0; d < names.size(); ++d)
    derived << (d ? ", " : "") << names[d] << " " << largest + 1 + static_cast<std::int32_t>(d);
  derived << "; int32 labels sha256 " << sha256_hex(bytes);
  result.provenance.push_back(derived.str());
  return result;
}

std::vector<std::filesystem::path> atlas_input_files(const std::string& atlas,
                                                     const std::filesystem::path& templates_dir) {
  std::filesystem::path labels, t1;
  if (is_segmentation_atlas(atlas, &labels, &t1)) return {labels, t1};
  if (atlas != "colin27") throw InputError("atlas: expected one of colin27, found '" + atlas + "'");
  return {templates_dir / "ch2.nii.gz", templates_dir / "ch2bet.nii.gz", templates_dir / "aal.nii.gz"};
}

AtlasLabels derive_atlas_labels(const std::string& atlas, const std::filesystem::path& templates_dir) {
  std::filesystem::path labels_file, t1_file;
  if (is_segmentation_atlas(atlas, &labels_file, &t1_file))
    return derive_segmentation_head(labels_file, t1_file);
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
