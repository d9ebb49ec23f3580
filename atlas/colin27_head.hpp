#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// Labels of the Colin 27 head volume (docs/anatomy-colin27.md).
enum Colin27Label : std::int32_t {
  colin27_background = 0,
  colin27_scalp = 1,        ///< the skin: the head's outer layer (skin_thickness_mm)
  colin27_skull = 2,        ///< bone between the outer CSF and the scalp
  colin27_csf = 3,          ///< outer (subarachnoid) and sulcal CSF
  colin27_cortical_gm = 4,  ///< cerebral grey matter outside the deep nuclei
  colin27_white_matter = 5, ///< cerebral white matter
  colin27_ventricles = 6,   ///< lateral ventricles (the largest deep CSF piece on each side)
  colin27_caudate = 7,
  colin27_putamen = 8,
  colin27_pallidum = 9,
  colin27_thalamus = 10,
  colin27_cerebellum = 11, ///< the cerebellar cortex (grey matter); its white matter is label 16
  colin27_brainstem = 12,
  colin27_subcutaneous_fat = 13,        ///< soft tissue under the skin brighter than white matter (fat)
  colin27_muscle = 14,                  ///< the other soft tissue under the skin (muscle, connective tissue)
  colin27_bone_marrow = 15,             ///< skull voxels brighter than bone, enclosed by skull (diploe)
  colin27_cerebellar_white_matter = 16, ///< the cerebellum's voxels of the brain's white-matter class
  colin27_eye = 17,                     ///< the eyeballs: the dark (vitreous) globes in the orbits
  colin27_orbital_fat = 18,             ///< the bright fat behind each eyeball, in its orbit
};

/// One row of the label table.
struct HeadLabelInfo {
  std::int32_t label = 0;
  std::string name;   ///< e.g. "lateral_ventricles"
  std::string tissue; ///< a tissue of core/data/tissues.csv ("gray_matter", "csf", ...), "" for background
};

/// A labelled head on a voxel grid.
struct HeadLabels {
  ImageGrid grid;                   ///< the grid of ch2.nii.gz (1 mm, 181 x 217 x 181)
  std::vector<std::int32_t> labels; ///< grid.voxel_count() labels, i fastest
  std::vector<HeadLabelInfo> table; ///< every label, background first, in label order
};

/// Parameters of the derivation; every length is in mm (world units), whatever the voxel size.
struct Colin27Options {
  int majority_filter_passes = 1;       ///< 3x3x3 majority passes over the tissue classes
  double outer_csf_thickness_mm = 1.5;  ///< outer CSF = brain mask dilated by this, minus the brain
  double scalp_thickness_mm = 5.0;      ///< scalp = head voxels this close to the head's surface
  double skull_min_thickness_mm = 3.0;  ///< skull voxels at least this far beyond the outer CSF
  double bone_intensity_fraction = 0.6; ///< outside the brain, T1 below this times the head threshold is bone
  double ventricle_depth_mm = 12.0;     ///< ventricles lie at least this deep inside the brain mask
  double ventricle_min_volume_ml = 1.0; ///< smaller deep CSF components are sulcal CSF
  double ventricle_midline_gap_mm = 2.0; ///< deep CSF this close to the midline (x) is not ventricle
  double brainstem_half_width_mm = 20.0; ///< brainstem candidates lie this close to the midline (x)
  /// Brainstem candidates lie under the thalamus from front to back, and up to this much behind it.
  double brainstem_posterior_mm = 14.0;
  /// Deep CSF this close to the brainstem or AAL's cerebellum is not lateral ventricle (the fourth
  /// ventricle, the aqueduct, the cisterns).
  double ventricle_clearance_mm = 3.0;
  /// CSF with thalamus on both sides along x, each within this distance, is the third ventricle.
  double third_ventricle_reach_mm = 12.0;
  /// A run of CSF along x at most this wide reaching into the midline slab is the interhemispheric
  /// fissure, not ventricle.
  double fissure_max_width_mm = 8.0;
  double skin_thickness_mm = 1.5; ///< skin = head voxels this close to the head's surface
  /// Under the skin, T1 at least this times the mean of the brain's white-matter class is fat
  /// (the brightest tissue of a T1w head); darker soft tissue is muscle.
  double fat_intensity_fraction = 1.15;
  /// Skull voxels enclosed by skull with T1 at least this times the white-matter mean are marrow
  /// (diploe); darker ones stay cortical bone.
  double marrow_intensity_fraction = 0.5;
  /// The orbits' search box (world RAS mm, the template's MNI space): |x|, y and z ranges. Each
  /// eye is the largest dark piece on its side within it.
  double orbit_abs_x_mm[2] = {12.0, 55.0};
  double orbit_y_mm[2] = {25.0, 85.0};
  double orbit_z_mm[2] = {-60.0, -15.0};
  /// Vitreous: T1 between these times the white-matter mean (darker than muscle, brighter than
  /// air and bone).
  double vitreous_intensity_fraction[2] = {0.23, 0.6};
  /// Erosions (then as many dilations) of the dark voxels that cut an eye from the dark bone and
  /// muscle touching it.
  int eye_opening_voxels = 2;
  /// Orbital fat: fat-bright voxels (fat_intensity_fraction) of the orbit box behind an eye's
  /// centre and within this distance of it.
  double orbital_fat_reach_mm = 28.0;
};

/// Derives the labelled Colin 27 head from the templates of Debian's mricron-data package
/// (ch2.nii.gz, ch2bet.nii.gz, aal.nii.gz): the method is in docs/anatomy-colin27.md.
/// Deterministic: the same files and options give the same labels, byte for byte.
/// @param templates_dir folder holding the templates (/usr/share/mricron/templates on Debian)
/// @param options parameters of the derivation
/// @throws InputError naming the missing or unreadable file and the Debian package
HeadLabels derive_colin27_head(const std::filesystem::path& templates_dir,
                               const Colin27Options& options = {});

/// The folder where Debian's mricron-data installs the templates.
std::filesystem::path default_colin27_templates_dir();

/// Volume of each label in ml (index = label), from the grid's voxel size.
std::vector<double> label_volumes_ml(const HeadLabels& head);

} // namespace phantasm
