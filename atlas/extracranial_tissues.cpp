#include "atlas/extracranial_tissues.hpp"

#include "atlas/voxel_masks.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace phantasm {
namespace {

using namespace voxel_masks;

/// Divides the tissue outside the skull (labelled scalp) into skin, subcutaneous fat and muscle,
/// lets the hook label more (the Colin head's eyes), and divides the
/// skull into cortical bone and marrow (see the comments inside).
void label_extracranial_tissues(const ImageGrid& grid, const std::vector<int>& intensity,
                                const std::vector<float>& from_outside, double white_matter_mean,
                                double bone_level, const Colin27Options& options,
                                const std::function<void(double, std::vector<std::int32_t>&)>& before_marrow,
                                std::vector<std::int32_t>& labels) {
  const Volume vol(grid);
  const std::size_t count = labels.size();
  // Skin: the head's outer layer. Under it, fat is what is brighter than the brain's white matter
  // (fat's short T1 makes it the brightest tissue of a T1w head), muscle the rest; one majority
  // pass as inside the brain drops single voxels of either.
  const double fat_level = options.fat_intensity_fraction * white_matter_mean;
  Mask soft(count);
  std::vector<std::int8_t> cls(count, 0);
  for (std::size_t n = 0; n < count; ++n) {
    if (labels[n] != colin27_scalp || from_outside[n] <= options.skin_thickness_mm) continue;
    soft[n] = 1;
    cls[n] = intensity[n] >= fat_level ? 2 : 1;
  }
  for (int pass = 0; pass < options.majority_filter_passes; ++pass)
    cls = majority_filter(cls, soft, grid);
  for (std::size_t n = 0; n < count; ++n)
    if (soft[n]) labels[n] = cls[n] == 2 ? colin27_subcutaneous_fat : colin27_muscle;
  // The Colin head's eyes and orbital fat come out of the skull, fat and muscle before the
  // marrow, which stays enclosed by the bone left.
  if (before_marrow) before_marrow(white_matter_mean, labels);
  // Marrow (diploe): skull voxels brighter than marrow_intensity_fraction times white matter
  // whose six neighbours are all skull, so that the cortical tables stay bone on both sides.
  const double marrow_level = std::max(bone_level, options.marrow_intensity_fraction * white_matter_mean);
  std::vector<std::int64_t> marrow;
  for (int k = 1; k < vol.nz - 1; ++k)
    for (int j = 1; j < vol.ny - 1; ++j)
      for (int i = 1; i < vol.nx - 1; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (labels[n] != colin27_skull || intensity[n] < marrow_level) continue;
        bool enclosed = true;
        for (const std::int64_t m : {n - 1, n + 1, n - vol.nx, n + vol.nx, n - std::int64_t(vol.nx) * vol.ny,
                                     n + std::int64_t(vol.nx) * vol.ny})
          enclosed = enclosed && labels[m] == colin27_skull;
        if (enclosed) marrow.push_back(n);
      }
  for (const std::int64_t n : marrow)
    labels[n] = colin27_bone_marrow;
}

/// Labels the voxels outside the brain: outer CSF, skull and scalp, then the tissues inside
/// scalp and skull (see the comments inside).
int label_outside_brain(const ImageGrid& grid, const Mask& brain, const std::vector<int>& intensity,
                        double white_matter_mean, const Colin27Options& options,
                        const std::function<void(double, std::vector<std::int32_t>&)>& before_marrow,
                        std::vector<std::int32_t>& labels) {
  const std::size_t count = labels.size();
  // Outside the brain. Head: T1 above Otsu's threshold of the whole volume, its largest
  // piece, holes filled (dark bone and sinuses are inside the head).
  std::array<std::int64_t, 256> histogram{};
  for (std::size_t n = 0; n < count; ++n)
    ++histogram[intensity[n]];
  const int head_threshold = otsu_threshold(histogram);
  Mask head_mask(count);
  for (std::size_t n = 0; n < count; ++n)
    head_mask[n] = intensity[n] > head_threshold || brain[n];
  head_mask = fill_holes_axial(fill_holes(largest_component(head_mask, grid), grid), grid);

  // Outer CSF: the brain mask dilated by the CSF thickness. Skull: from there, at least the
  // minimum thickness, and further out every dark (bone) voxel. Scalp: the outer layer of the
  // head and every other non-bone voxel outside the skull.
  const std::vector<float> from_brain = distance_to(brain, grid);
  Mask not_head(count);
  for (std::size_t n = 0; n < count; ++n)
    not_head[n] = !head_mask[n];
  const std::vector<float> from_outside = distance_to(not_head, grid);
  const double bone_level = options.bone_intensity_fraction * head_threshold;
  for (std::size_t n = 0; n < count; ++n) {
    if (brain[n]) continue;
    const double d = from_brain[n];
    if (d <= options.outer_csf_thickness_mm) {
      labels[n] = colin27_csf;
      continue;
    }
    if (!head_mask[n]) continue;
    const bool in_scalp = from_outside[n] <= options.scalp_thickness_mm;
    const bool in_min_skull = d <= options.outer_csf_thickness_mm + options.skull_min_thickness_mm;
    if (in_min_skull && !in_scalp)
      labels[n] = colin27_skull;
    else if (!in_scalp && intensity[n] < bone_level)
      labels[n] = colin27_skull;
    else
      labels[n] = colin27_scalp;
  }
  label_extracranial_tissues(grid, intensity, from_outside, white_matter_mean, bone_level, options,
                             before_marrow, labels);
  return head_threshold;
}

} // namespace

std::vector<int> t1_levels(const std::vector<double>& values) {
  bool eight_bit = true;
  for (const double v : values)
    eight_bit = eight_bit && v >= 0.0 && v <= 255.0;
  std::vector<int> levels(values.size());
  if (eight_bit) {
    for (std::size_t n = 0; n < values.size(); ++n)
      levels[n] = std::clamp(static_cast<int>(std::lround(values[n])), 0, 255);
    return levels;
  }
  std::vector<double> positive;
  for (const double v : values)
    if (v > 0.0 && std::isfinite(v)) positive.push_back(v);
  double top = 1.0;
  if (!positive.empty()) {
    const std::size_t at = static_cast<std::size_t>(0.995 * double(positive.size() - 1));
    std::nth_element(positive.begin(), positive.begin() + static_cast<std::ptrdiff_t>(at), positive.end());
    top = positive[at] > 0.0 ? positive[at] : 1.0;
  }
  for (std::size_t n = 0; n < values.size(); ++n) {
    const double scaled = std::isfinite(values[n]) ? values[n] * 255.0 / top : 0.0;
    levels[n] = static_cast<int>(std::lround(std::clamp(scaled, 0.0, 255.0)));
  }
  return levels;
}

ExtracranialTissues derive_extracranial_tissues(
    const ImageGrid& grid, const std::vector<int>& t1, const std::vector<std::uint8_t>& brain,
    const std::vector<std::uint8_t>& white_matter, const Colin27Options& options,
    const std::function<void(double white_matter_mean, std::vector<std::int32_t>& labels)>& before_marrow) {
  ExtracranialTissues out;
  const std::size_t count = t1.size();
  // The brain's white matter: the reference level of the tissues outside it.
  double white_matter_sum = 0.0;
  std::int64_t white_matter_voxels = 0;
  for (std::size_t n = 0; n < count; ++n)
    if (white_matter[n]) {
      white_matter_sum += t1[n];
      ++white_matter_voxels;
    }
  out.white_matter_mean = white_matter_voxels > 0 ? white_matter_sum / double(white_matter_voxels) : 255.0;
  out.labels.assign(count, colin27_background);
  out.head_threshold =
      label_outside_brain(grid, brain, t1, out.white_matter_mean, options, before_marrow, out.labels);
  return out;
}

} // namespace phantasm
