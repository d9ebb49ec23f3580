#include "atlas/colin27_head.hpp"

#include "atlas/extracranial_tissues.hpp"
#include "atlas/voxel_masks.hpp"
#include "core/error.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace phantasm {
namespace {

using namespace voxel_masks;

constexpr const char* debian_package = "mricron-data";

std::filesystem::path require_template(const std::filesystem::path& folder, const std::string& name) {
  const std::filesystem::path path = folder / name;
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError("colin27: template " + path.string() + " not found; it comes with the Debian package " +
                     debian_package + " (apt-get install " + debian_package +
                     ", or scripts/install-deps.sh), or pass the folder holding it");
  }
  return path;
}

/// AAL index ranges (aal.nii.txt: "index name code").
bool aal_is(int index, int first, int last) {
  return index >= first && index <= last;
}

/// Where the thalami lie (mm): their lowest point, front and back ends, and the midline (their mean x).
struct ThalamusExtent {
  double min_z = std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();
  double midline_x = 0.0;
};

ThalamusExtent thalamus_extent(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                               const std::vector<int>& aal) {
  ThalamusExtent extent;
  double x_sum = 0.0;
  std::int64_t voxels = 0;
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || !aal_is(aal[n], 77, 78)) continue;
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(i, j, k));
        extent.min_z = std::min(extent.min_z, p.z());
        extent.min_y = std::min(extent.min_y, p.y());
        extent.max_y = std::max(extent.max_y, p.y());
        x_sum += p.x();
        ++voxels;
      }
  if (voxels > 0) extent.midline_x = x_sum / double(voxels);
  return extent;
}

/// Marks in `out` every run of CSF-class voxels along x, at most `fissure_max_width_mm` wide, that
/// comes within `ventricle_midline_gap_mm` of the midline: the interhemispheric fissure.
void mark_fissure(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                  const std::vector<std::int8_t>& cls, double midline_x, const Colin27Options& options,
                  Mask& out) {
  const auto x_of = [&](int i, int j, int k) { return grid.world_from_index(Eigen::Vector3d(i, j, k)).x(); };
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx;) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || cls[n] != 1) {
          ++i;
          continue;
        }
        int end = i;
        double nearest = std::abs(x_of(i, j, k) - midline_x);
        while (end + 1 < vol.nx && brain[vol.at(end + 1, j, k)] && cls[vol.at(end + 1, j, k)] == 1) {
          ++end;
          nearest = std::min(nearest, std::abs(x_of(end, j, k) - midline_x));
        }
        const double width = std::abs(x_of(end, j, k) - x_of(i, j, k)) + grid.spacing_mm.x();
        if (nearest < options.ventricle_midline_gap_mm && width <= options.fissure_max_width_mm)
          for (int m = i; m <= end; ++m)
            out[static_cast<std::size_t>(vol.at(m, j, k))] = 1;
        i = end + 1;
      }
}

/// The CSF that is not a lateral ventricle however deep it lies: the third ventricle (voxels with
/// thalamus on both sides along x, each within `third_ventricle_reach_mm`) and the fourth
/// ventricle, the aqueduct and the cisterns around the brainstem and the cerebellum (voxels within
/// `ventricle_clearance_mm` of either), and the interhemispheric fissure where it leaves the
/// midline slab (a run of CSF along x, at most `fissure_max_width_mm` wide, that reaches into the
/// slab: the fissure is not straight, and beside the slab it joined the ventricles).
Mask not_lateral_ventricle(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                           const std::vector<int>& aal, const std::vector<std::int8_t>& cls,
                           const Mask& brainstem, const ThalamusExtent& thalamus,
                           const Colin27Options& options) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  Mask hindbrain(count);
  for (std::size_t n = 0; n < count; ++n)
    hindbrain[n] = brainstem[n] || (brain[n] && aal_is(aal[n], 91, 116));
  const std::vector<float> from_hindbrain = distance_to(hindbrain, grid);
  Mask out(count);
  for (std::size_t n = 0; n < count; ++n)
    out[n] = from_hindbrain[n] <= options.ventricle_clearance_mm;
  const int reach = static_cast<int>(std::floor(options.third_ventricle_reach_mm / grid.spacing_mm.x()));
  // Per voxel: 1 thalamus left of the midline (x below it), 2 right of it, 0 none.
  std::vector<std::int8_t> side(count, 0);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || !aal_is(aal[n], 77, 78)) continue;
        side[n] = grid.world_from_index(Eigen::Vector3d(i, j, k)).x() < thalamus.midline_x ? 1 : 2;
      }
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || side[n] != 0) continue;
        int found = 0; // bit 1: left thalamus within reach, bit 2: right
        for (int s = std::max(0, i - reach); s <= std::min(vol.nx - 1, i + reach); ++s)
          found |= side[static_cast<std::size_t>(vol.at(s, j, k))];
        if (found == 3) out[n] = 1;
      }
  mark_fissure(grid, vol, brain, cls, thalamus.midline_x, options, out);
  return out;
}

/// The lateral ventricles: per CSF component of the deep, off-midline CSF-class voxels, whether
/// it is one (the largest piece on each side of the midline, if at least the minimum volume).
/// `csf_component` receives each voxel's component (0: none).
std::vector<std::uint8_t> lateral_ventricles(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                                             const std::vector<std::int8_t>& cls, const Mask& not_ventricle,
                                             double midline_x, const Colin27Options& options,
                                             std::vector<std::int32_t>& csf_component) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  // Lateral ventricles: CSF-class voxels deep inside the brain (never near the brain's outer
  // rim, where sulcal CSF is), off a thin midline slab (which cuts the interhemispheric
  // fissure's CSF from them, as the septum pellucidum does) and outside `not_ventricle` (the
  // third and fourth ventricles and the cisterns), then on each side of the midline the largest
  // connected piece, if at least the minimum volume.
  Mask not_brain(count);
  for (std::size_t n = 0; n < count; ++n)
    not_brain[n] = !brain[n];
  const std::vector<float> depth = distance_to(not_brain, grid);
  Mask deep_csf(count);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (cls[n] != 1 || depth[n] < options.ventricle_depth_mm || not_ventricle[n]) continue;
        const double x = grid.world_from_index(Eigen::Vector3d(i, j, k)).x();
        deep_csf[n] = std::abs(x - midline_x) >= options.ventricle_midline_gap_mm;
      }
  std::int32_t csf_components = 0;
  csf_component = connected_components(deep_csf, grid, &csf_components);
  std::vector<std::int64_t> csf_size(static_cast<std::size_t>(csf_components) + 1, 0);
  std::vector<double> csf_x(static_cast<std::size_t>(csf_components) + 1, 0.0);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int32_t c = csf_component[vol.at(i, j, k)];
        ++csf_size[c];
        csf_x[c] += grid.world_from_index(Eigen::Vector3d(i, j, k)).x();
      }
  const double voxel_ml = grid.spacing_mm.prod() / 1000.0;
  std::array<std::int32_t, 2> largest{0, 0}; // left (x < midline), right
  for (std::int32_t c = 1; c <= csf_components; ++c) {
    const int side = csf_x[c] / double(csf_size[c]) < midline_x ? 0 : 1;
    if (largest[side] == 0 || csf_size[c] > csf_size[largest[side]]) largest[side] = c;
  }
  std::vector<std::uint8_t> is_ventricle(static_cast<std::size_t>(csf_components) + 1, 0);
  for (const std::int32_t c : largest)
    if (c != 0 && double(csf_size[c]) * voxel_ml >= options.ventricle_min_volume_ml) is_ventricle[c] = 1;

  return is_ventricle;
}

/// The brainstem (see the comment inside).
Mask brainstem_mask(const ImageGrid& grid, const Volume& vol, const Mask& brain, const std::vector<int>& aal,
                    const std::vector<std::int8_t>& cls, const ThalamusExtent& thalamus,
                    const Colin27Options& options) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  // Brainstem: the unlabelled part of the brain below the thalamus near the midline. AAL
  // labels grey matter only, so its zero inside the brain is white matter or brainstem; below
  // the thalamus's lowest point, within a slab around the midline and under the thalamus from
  // front to back (extended backwards: the medulla leans back), the largest connected piece of
  // it (CSF excluded) is the brainstem. Without the front and back limits it took the frontal
  // lobe's basal white matter (up to 60 mm in front of the pons) and the cerebellum's.
  Mask stem_candidate(count);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || aal[n] != 0 || cls[n] == 1) continue;
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(i, j, k));
        stem_candidate[n] = p.z() < thalamus.min_z &&
                            std::abs(p.x() - thalamus.midline_x) <= options.brainstem_half_width_mm &&
                            p.y() <= thalamus.max_y &&
                            p.y() >= thalamus.min_y - options.brainstem_posterior_mm;
      }
  return largest_component(stem_candidate, grid);
}

/// Labels the brain's voxels: the atlas's deep nuclei (which win over the ventricles they border:
/// CSF partial volume at their edges is the atlas's call), the lateral ventricles, CSF, the
/// cerebellum (AAL's, and below the thalamus the unlabelled non-CSF voxels nearer to AAL's
/// cerebellum than to its cerebrum: the cerebellum's white matter, which AAL leaves unlabelled
/// as it does the cerebrum's; its voxels of the white-matter class are cerebellar white matter,
/// the rest its cortex), the brainstem, then white or cortical grey matter by class.
template <class IsVentricle>
void label_brain(const ImageGrid& grid, const Volume& vol, const Mask& brain, const std::vector<int>& aal,
                 const std::vector<std::int8_t>& cls, const Mask& brainstem, const ThalamusExtent& thalamus,
                 IsVentricle&& is_ventricle, std::vector<std::int32_t>& labels) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  Mask cerebellum(count), cerebrum(count);
  for (std::size_t n = 0; n < count; ++n) {
    cerebellum[n] = brain[n] && aal_is(aal[n], 91, 116);
    cerebrum[n] = brain[n] && aal_is(aal[n], 1, 90);
  }
  const std::vector<float> from_cerebellum = distance_to(cerebellum, grid);
  const std::vector<float> from_cerebrum = distance_to(cerebrum, grid);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n]) continue;
        const int a = aal[n];
        // Inside the cerebellum the brain's white-matter class (step 2) is its white matter.
        const std::int32_t cerebellar = cls[n] == 3 ? colin27_cerebellar_white_matter : colin27_cerebellum;
        if (aal_is(a, 71, 72))
          labels[n] = colin27_caudate;
        else if (aal_is(a, 73, 74))
          labels[n] = colin27_putamen;
        else if (aal_is(a, 75, 76))
          labels[n] = colin27_pallidum;
        else if (aal_is(a, 77, 78))
          labels[n] = colin27_thalamus;
        else if (is_ventricle(n))
          labels[n] = colin27_ventricles;
        else if (cls[n] == 1)
          labels[n] = colin27_csf;
        else if (aal_is(a, 91, 116))
          labels[n] = cerebellar;
        else if (brainstem[n])
          labels[n] = colin27_brainstem;
        else if (a == 0 && from_cerebellum[n] < from_cerebrum[n] &&
                 grid.world_from_index(Eigen::Vector3d(i, j, k)).z() < thalamus.min_z)
          labels[n] = cerebellar;
        else
          labels[n] = cls[n] == 3 ? colin27_white_matter : colin27_cortical_gm;
      }
}

/// The eyes and the orbital fat behind them (see the comments inside); labels them in place.
void label_eyes(const ImageGrid& grid, const std::vector<int>& intensity, double white_matter_mean,
                const Colin27Options& options, std::vector<std::int32_t>& labels) {
  const Volume vol(grid);
  const std::size_t count = labels.size();
  const auto extracranial = [](std::int32_t l) {
    return l == colin27_skull || l == colin27_subcutaneous_fat || l == colin27_muscle;
  };
  const auto world = [&grid, &vol](std::int64_t n) {
    return grid.world_from_index(Eigen::Vector3d(double(n % vol.nx), double((n / vol.nx) % vol.ny),
                                                 double(n / (std::int64_t(vol.nx) * vol.ny))));
  };
  Mask in_box(count);
  for (std::int64_t n = 0; n < vol.size(); ++n) {
    const Eigen::Vector3d x = world(n);
    in_box[n] = std::abs(x.x()) >= options.orbit_abs_x_mm[0] &&
                std::abs(x.x()) <= options.orbit_abs_x_mm[1] && x.y() >= options.orbit_y_mm[0] &&
                x.y() <= options.orbit_y_mm[1] && x.z() >= options.orbit_z_mm[0] &&
                x.z() <= options.orbit_z_mm[1];
  }
  // Vitreous is darker than muscle and brighter than air and cortical bone: within the orbit box,
  // under the skin and outside the skull's cavity, the voxels of that range, opened to cut them
  // from the dark bone and muscle they touch; each side's largest piece, holes filled (the lens),
  // is its eye.
  Mask dark(count);
  for (std::size_t n = 0; n < count; ++n)
    dark[n] = in_box[n] && extracranial(labels[n]) &&
              intensity[n] >= options.vitreous_intensity_fraction[0] * white_matter_mean &&
              intensity[n] <= options.vitreous_intensity_fraction[1] * white_matter_mean;
  for (int e = 0; e < options.eye_opening_voxels; ++e)
    dark = step_mask(dark, grid, true);
  for (int e = 0; e < options.eye_opening_voxels; ++e)
    dark = step_mask(dark, grid, false);
  const double fat_level = options.fat_intensity_fraction * white_matter_mean;
  for (const double side : {-1.0, 1.0}) {
    Mask half(count);
    for (std::size_t n = 0; n < count; ++n)
      half[n] = dark[n] && in_box[n] && world(std::int64_t(n)).x() * side > 0.0;
    const Mask eye = fill_holes(largest_component(half, grid), grid);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::int64_t voxels = 0;
    for (std::size_t n = 0; n < count; ++n)
      if (eye[n] && extracranial(labels[n])) {
        labels[n] = colin27_eye;
        centre += world(std::int64_t(n));
        ++voxels;
      }
    if (voxels == 0) continue;
    centre /= double(voxels);
    // Orbital fat: the fat-bright voxels behind the eye's centre, within reach of it.
    for (std::size_t n = 0; n < count; ++n)
      if (in_box[n] && extracranial(labels[n]) && intensity[n] >= fat_level &&
          world(std::int64_t(n)).y() < centre.y() &&
          (world(std::int64_t(n)) - centre).norm() <= options.orbital_fat_reach_mm)
        labels[n] = colin27_orbital_fat;
  }
}

} // namespace

std::filesystem::path default_colin27_templates_dir() {
  return "/usr/share/mricron/templates";
}

HeadLabels derive_colin27_head(const std::filesystem::path& templates_dir, const Colin27Options& options) {
  if (!std::filesystem::is_directory(templates_dir)) {
    throw InputError("colin27: templates folder " + templates_dir.string() +
                     " not found; it comes with the Debian package " + debian_package + " (apt-get install " +
                     debian_package + ", or scripts/install-deps.sh)");
  }
  const NiftiVolume t1 = read_nifti(require_template(templates_dir, "ch2.nii.gz"));
  const NiftiVolume bet = read_nifti(require_template(templates_dir, "ch2bet.nii.gz"));
  const NiftiVolume aal_file = read_nifti(require_template(templates_dir, "aal.nii.gz"));

  HeadLabels head;
  head.grid = t1.grid;
  const ImageGrid& grid = head.grid;
  const Volume vol(grid);
  const std::size_t count = static_cast<std::size_t>(vol.size());
  const std::vector<double> bet_values = resample_nearest(bet, grid);
  const std::vector<double> aal_values = resample_nearest(aal_file, grid);
  std::vector<int> aal(count);
  for (std::size_t n = 0; n < count; ++n)
    aal[n] = static_cast<int>(std::lround(aal_values[n]));
  const std::vector<int> intensity = t1_levels(t1.values);

  // Brain: the brain-extracted template's support, holes filled (dark ventricles stay inside).
  Mask brain(count);
  for (std::size_t n = 0; n < count; ++n)
    brain[n] = bet_values[n] > 0.0;
  brain = fill_holes(largest_component(brain, grid), grid);

  // Tissue classes inside the brain: 1 CSF, 2 GM, 3 WM (T1: CSF darkest, WM brightest).
  std::array<std::int64_t, 256> brain_histogram{};
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n]) ++brain_histogram[intensity[n]];
  const std::array<double, 2> cut = three_class_thresholds(brain_histogram);
  std::vector<std::int8_t> cls(count, 0);
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n])
      cls[n] = static_cast<std::int8_t>(intensity[n] < cut[0] ? 1 : (intensity[n] < cut[1] ? 2 : 3));
  for (int pass = 0; pass < options.majority_filter_passes; ++pass)
    cls = majority_filter(cls, brain, grid);

  const ThalamusExtent thalamus = thalamus_extent(grid, vol, brain, aal);
  const Mask brainstem = brainstem_mask(grid, vol, brain, aal, cls, thalamus, options);
  std::vector<std::int32_t> csf_component;
  const std::vector<std::uint8_t> is_ventricle = lateral_ventricles(
      grid, vol, brain, cls, not_lateral_ventricle(grid, vol, brain, aal, cls, brainstem, thalamus, options),
      thalamus.midline_x, options, csf_component);
  head.labels.assign(count, colin27_background);
  label_brain(
      grid, vol, brain, aal, cls, brainstem, thalamus,
      [&](std::int64_t n) { return is_ventricle[csf_component[n]] != 0; }, head.labels);
  std::vector<std::int32_t>& labels = head.labels;

  // Outside the brain: the tissues the T1 shows (atlas/extracranial_tissues.hpp), the brain's
  // white-matter class their reference level, and the eyes taken out of them before the marrow.
  Mask white_matter(count);
  for (std::size_t n = 0; n < count; ++n)
    white_matter[n] = cls[n] == 3;
  const ExtracranialTissues outside =
      derive_extracranial_tissues(grid, intensity, brain, white_matter, options,
                                  [&](double white_matter_mean, std::vector<std::int32_t>& extracranial) {
                                    label_eyes(grid, intensity, white_matter_mean, options, extracranial);
                                  });
  for (std::size_t n = 0; n < count; ++n)
    if (outside.labels[n] != colin27_background) labels[n] = outside.labels[n];

  head.table = {{colin27_background, "background", ""},
                {colin27_scalp, "scalp", "skin"}, // the skin alone (the tissues under it below)
                {colin27_skull, "skull", "bone_cortical"},
                {colin27_csf, "csf", "csf"},
                {colin27_cortical_gm, "cortical_grey_matter", "gray_matter"},
                {colin27_white_matter, "white_matter", "white_matter"},
                {colin27_ventricles, "lateral_ventricles", "csf"},
                {colin27_caudate, "caudate", "gray_matter"},
                {colin27_putamen, "putamen", "gray_matter"},
                {colin27_pallidum, "pallidum", "gray_matter"},
                {colin27_thalamus, "thalamus", "gray_matter"},
                {colin27_cerebellum, "cerebellum", "gray_matter"},
                {colin27_brainstem, "brainstem", "white_matter"},
                {colin27_subcutaneous_fat, "subcutaneous_fat", "fat_subcutaneous"},
                {colin27_muscle, "muscle", "muscle_skeletal"},
                {colin27_bone_marrow, "bone_marrow", "bone_marrow"},
                {colin27_cerebellar_white_matter, "cerebellar_white_matter", "white_matter"},
                {colin27_eye, "eye", "vitreous"},
                {colin27_orbital_fat, "orbital_fat", "fat_subcutaneous"}};
  return head;
}

std::vector<double> label_volumes_ml(const HeadLabels& head) {
  std::int32_t max_label = 0;
  for (const HeadLabelInfo& info : head.table)
    max_label = std::max(max_label, info.label);
  for (const std::int32_t l : head.labels)
    max_label = std::max(max_label, l);
  std::vector<std::int64_t> counts(static_cast<std::size_t>(max_label) + 1, 0);
  for (const std::int32_t l : head.labels)
    if (l >= 0) ++counts[static_cast<std::size_t>(l)];
  const double voxel_ml = head.grid.spacing_mm.prod() / 1000.0;
  std::vector<double> volumes(counts.size());
  for (std::size_t l = 0; l < counts.size(); ++l)
    volumes[l] = double(counts[l]) * voxel_ml;
  return volumes;
}

} // namespace phantasm
