// The settings the MR stage reads (field strength, tissues, sequences, acquisition), filled and
// resolved by the scene parser; Eigen and the standard library only.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A scene-supplied tissue value that replaces or completes the built-in table.
struct TissueOverride {
  std::string tissue;
  std::optional<double> T1_ms, T2_ms, T2star_ms, PD;
};

enum class SequenceKind { spin_echo, spoiled_gre, inversion_recovery, bssfp, mprage };
enum class Readout { gradient_echo, spin_echo };
/// How the images' voxels are stored: as a scanner writes them (whole numbers) or as floats.
enum class ImageDatatype { float32, int16, uint16 };

/// The level at which the automatic receiver gain puts the reference tissue's signal
/// (automatic_receiver_gain()): a T1w head's white matter at 1000, as scanners write it.
inline constexpr double k_receiver_reference_level = 1000.0;

/// One MR image to make, named by its BIDS suffix.
struct SequenceSettings {
  std::string name; ///< BIDS suffix, e.g. T1w, T2w, PDw, FLAIR, T2starw, UNIT1
  SequenceKind kind = SequenceKind::spin_echo;
  double TR_ms = 0.0;
  double TE_ms = 0.0; ///< bSSFP: TR_ms / 2 unless the scene gives it (set by the scene parser)
  double flip_deg = 90.0;
  double TI_ms = 0.0;                       ///< inversion recovery and MPRAGE
  Readout readout = Readout::gradient_echo; ///< inversion recovery
  double echo_spacing_ms = 0.0;             ///< MPRAGE: gradient-echo spacing in the train
  int turbo_factor = 0;                     ///< MPRAGE: echoes per inversion
};

struct AcquisitionSettings {
  bool kspace = false;         ///< simulate k-space truncation (Gibbs ringing)
  int kspace_oversampling = 2; ///< object samples per acquired sample along each axis
  /// Acquired voxel size along i, j, k (replaces kspace_oversampling; anisotropic allowed).
  std::optional<Eigen::Vector3d> acquired_voxel_mm;
  double slice_thickness_mm = 0.0; ///< rectangular slice profile along k; 0 = none (3-D acquisition)
  double noise_percent = 0.0;      ///< 100 sigma / signal of the reference tissue (BrainWeb)
  std::string noise_reference_tissue = "white_matter";
  double bias_percent = 0.0; ///< peak-to-peak multiplicative bias field, percent
  int coils = 1;             ///< receive coils combined by sum of squares
  /// Scanner units per proton-density unit, the same for every image; empty: each sequence's
  /// automatic gain (automatic_receiver_gain()).
  std::optional<double> receiver_gain;
  ImageDatatype image_datatype = ImageDatatype::float32; ///< how the image files store voxels
};

/// A tissue region (docs/volumes-and-images.md, "Tissue regions and texture"): the voxels of an
/// organ that the organ's atlas gives `label` take `tissue` and a dseg label of their own, named
/// after the atlas label. Made in the reference state and carried to the deformed one by the
/// exact map, so that a region moves with the tissue.
struct TissueRegionSettings {
  std::string organ;  ///< an organ whose shape is a label volume of an atlas
  std::string label;  ///< a label name of that atlas
  std::string tissue; ///< a tissue of the built-in table or of the scene's tissues section
  std::string name;   ///< its dseg name; empty: the label's (region_name)
};

/// A region's dseg name: its own name, or its atlas label's.
inline const std::string& region_name(const TissueRegionSettings& region) {
  return region.name.empty() ? region.label : region.name;
}

/// Where a texture's deviations come from.
enum class TextureSource { none, scan, random };

/// Where a random texture's figures (standard deviation and correlation length) come from.
enum class RandomSpectrum { given, scan };

/// Spatial variation of T1 and PD within tissues (docs/volumes-and-images.md, "Tissue regions and
/// texture"): off by default.
struct TextureSettings {
  TextureSource source = TextureSource::none;
  std::vector<std::string> tissues; ///< the textured tissues; empty: every tissue
  std::string scan;                 ///< source scan: a NIfTI file; empty: the atlas's T1 scan (ch2.nii.gz)
  double T1_gain = 1.0;             ///< T1 x exp(-T1_gain d) for a relative deviation d
  double PD_gain = 0.25;            ///< PD x exp(PD_gain d)
  double max_deviation = 0.3;       ///< d clamped to +-max_deviation
  double random_sd = 0.05;          ///< random: standard deviation of d
  double correlation_mm = 2.0;      ///< random: the smoothing Gaussian's standard deviation
  /// random: given, one field with random_sd and correlation_mm; scan, a field per tissue with the
  /// standard deviation and correlation length measured on the scan (voxelize/texture_spectrum.hpp)
  RandomSpectrum spectrum = RandomSpectrum::given;
  /// a sequence of the scene, or empty: each textured tissue's T1 gain is then set so that this
  /// sequence's signal changes by d for a deviation d (to first order), instead of T1_gain
  std::string match;
};

const char* to_string(TextureSource source);

struct MriSettings {
  double field_strength_T = 3.0;
  std::vector<TissueOverride> tissues;
  std::vector<SequenceSettings> sequences;
  AcquisitionSettings acquisition;
  std::vector<TissueRegionSettings> regions; ///< tissue regions within organs (scene key tissue_regions)
  TextureSettings texture;                   ///< scene key texture

  // Set by the scene from other sections.
  std::uint64_t seed = 0;     ///< the scene's seed (noise, bias field)
  bool images = true;         ///< outputs.images
  bool parameter_maps = true; ///< outputs.parameter_maps: PD, T1, T2, T2* maps of each state
};

const char* to_string(SequenceKind kind);
const char* to_string(Readout readout);
const char* to_string(ImageDatatype datatype);

/// The receiver gain of one sequence when the scene gives none: the reference tissue's signal
/// (noise_reference_tissue, in proton-density units) lands at k_receiver_reference_level, unless
/// that would put the brightest tissue beyond 20 times the level (a reference tissue nulled or
/// nearly so); then the brightest lands at 20 times the level. 1 when no tissue gives signal.
/// @param reference_signal the reference tissue's signal; 0 when it is not in the phantom
/// @param brightest_signal the largest signal magnitude of the phantom's tissues
double automatic_receiver_gain(double reference_signal, double brightest_signal);

} // namespace phantasm
