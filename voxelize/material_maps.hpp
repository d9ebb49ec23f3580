// Volumes attached to the material: a reference-space label or parameter volume that the deformed
// state reads through the exact map, so that what it holds moves with the tissue. Tissue regions
// (the voxels of an organ that an atlas labels otherwise take a tissue of their own) and texture
// (a per-voxel factor of T1 and PD) are both made this way (docs/volumes-and-images.md, "Tissue
// regions and texture").
#pragma once

#include "core/grid.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace phantasm {

/// The label of `labels` (on `source`) at the voxel nearest a world point (RAS mm); `outside`
/// beyond the source's grid.
std::int32_t label_at(const ImageGrid& source, const std::vector<std::int32_t>& labels,
                      const Eigen::Vector3d& world_mm, std::int32_t outside = 0);

/// The value of `values` (on `source`) at a world point, trilinear between voxel centres;
/// `outside` beyond the outermost voxel centres.
float value_at(const ImageGrid& source, const std::vector<float>& values, const Eigen::Vector3d& world_mm,
               float outside);

/// A label volume on `source` sampled at the voxel centres of `target` (nearest voxel).
std::vector<std::int32_t> resample_labels(const ImageGrid& target, const ImageGrid& source,
                                          const std::vector<std::int32_t>& labels);

/// A scalar volume on `source` sampled at the voxel centres of `target` (trilinear).
std::vector<float> resample_values(const ImageGrid& target, const ImageGrid& source,
                                   const std::vector<float>& values, float outside);

/// A reference-space label volume on `grid` carried to the deformed state: the label at deformed
/// voxel x is the reference's at x + u(x) (nearest voxel), u the displacement on the deformed
/// grid that gives each deformed point's reference position (MotionFields::def_to_ref; in the
/// dataset, from-ref_to-def).
std::vector<std::int32_t> carry_labels(const ImageGrid& grid, const std::vector<std::int32_t>& reference,
                                       const std::vector<float>& def_to_ref);

/// A reference-space scalar volume carried to the deformed state as carry_labels() does, trilinear.
std::vector<float> carry_values(const ImageGrid& grid, const std::vector<float>& reference,
                                const std::vector<float>& def_to_ref, float outside);

/// One tissue region: the voxels of organ `organ_label` whose region label (an atlas label, in
/// the reference state) is `region_value` take `tissue` and the dseg label `label`.
struct TissueRegion {
  std::string name;              ///< the dseg name
  std::int32_t organ_label = 0;  ///< the organ's dseg label
  std::int32_t region_value = 0; ///< the value of the region volume that selects it
  std::int32_t label = 0;        ///< its dseg label
  int tissue = 0;                ///< index into the phantom's tissue list
  std::string atlas_label;       ///< the name of the atlas label that selects it (for the log)
};

/// Adds tissue columns to a state's stored fractions so that it holds `tissue_count` tissues (the
/// new ones empty everywhere); the background's column stays last.
void widen_tissues(TissueVolumes& volumes, int tissue_count);

/// Relabels the voxels of each region: a voxel whose label is a region's organ and whose value in
/// `region_volume` (one per voxel of the state's grid) is the region's takes the region's label,
/// and the organ tissue's fraction in it becomes the region tissue's. The volumes must already
/// hold every region's tissue (widen_tissues()).
/// @return the voxels relabelled per region, in the order of `regions`
std::vector<std::size_t> apply_tissue_regions(TissueVolumes& volumes,
                                              const std::vector<std::int32_t>& region_volume,
                                              const std::vector<TissueRegion>& regions);

/// The region volume the deformed state carries: `region_volume`'s value where the reference
/// state's voxel took one of `regions` (apply_tissue_regions() run on `reference_labels`), and
/// k_no_region elsewhere. Carried by the exact map, a deformed voxel of a region's organ takes the
/// region where its reference position lies in the region, not wherever the atlas labels it so: a
/// region whose label also lies outside the organ (the cerebrum's voxels the atlas labels csf)
/// does not grow along the organ's moved surface where the nearest reference voxel is the outer one.
std::vector<std::int32_t> held_region_values(const std::vector<std::int32_t>& reference_labels,
                                             const std::vector<std::int32_t>& region_volume,
                                             const std::vector<TissueRegion>& regions);

/// The value of held_region_values() outside every region: no region's.
constexpr std::int32_t k_no_region = std::numeric_limits<std::int32_t>::min();

/// How a texture turns a relative deviation d of a tissue's intensity into factors of its T1 and
/// PD: T1 x exp(-T1_gain d), PD x exp(PD_gain d), d clamped to +-max_deviation.
struct TextureGains {
  double T1_gain = 1.0;
  double PD_gain = 0.25;
  double max_deviation = 0.3;
  /// per tissue of the volumes, its own T1 gain (a voxel takes its label tissue's); empty: T1_gain
  std::vector<double> T1_gain_by_tissue = {};

  double T1_gain_of(int tissue) const {
    return static_cast<std::size_t>(tissue) < T1_gain_by_tissue.size()
               ? T1_gain_by_tissue[static_cast<std::size_t>(tissue)]
               : T1_gain;
  }
};

/// A texture from a scan: within each textured tissue (the tissue a voxel's label fills it with),
/// the scan's intensity (on the state's grid) relative to its mean over the tissue's voxels, less
/// one, is the deviation d.
/// @param textured per tissue of the volumes: whether it gets texture
/// @throws std::invalid_argument for an intensity volume of another grid
TextureMaps texture_from_intensity(const TissueVolumes& volumes, const std::vector<bool>& textured,
                                   const std::vector<float>& intensity, const TextureGains& gains);

/// A texture from a seeded random field: white Gaussian noise smoothed by a Gaussian of standard
/// deviation correlation_mm, scaled to standard deviation `deviation_sd` over the textured voxels,
/// is the deviation d. The same seed gives the same field.
TextureMaps texture_from_random_field(const ImageGrid& grid, const TissueVolumes& volumes,
                                      const std::vector<bool>& textured, std::uint64_t seed,
                                      double correlation_mm, double deviation_sd, const TextureGains& gains);

/// The figures of one tissue's random texture.
struct TextureField {
  double deviation_sd = 0.0;   ///< standard deviation of d over the tissue's voxels
  double correlation_mm = 0.0; ///< standard deviation of the Gaussian that smooths the white noise
};

/// A texture from seeded random fields, one per textured tissue, each with its own figures (as
/// measured on a scan: voxelize/texture_spectrum.hpp): for tissue t, white Gaussian noise drawn
/// from a generator seeded by `seed` and t over the box of the tissue's voxels (widened by three
/// of its smoothing Gaussian's standard deviations, past the grid's edges if need be, so that no
/// edge falls within the smoothing's reach of a tissue voxel), smoothed, scaled to
/// fields[t].deviation_sd over the tissue's voxels, is the deviation d of those voxels. The same
/// seed gives the same maps.
/// @param fields per tissue of the volumes (used for the textured ones)
/// @throws std::invalid_argument for volumes of another grid or too few fields
TextureMaps texture_from_random_fields(const ImageGrid& grid, const TissueVolumes& volumes,
                                       const std::vector<bool>& textured, std::uint64_t seed,
                                       const std::vector<TextureField>& fields, const TextureGains& gains);

/// The reference state's texture carried to the deformed state (carry_values(), 1 outside the grid).
TextureMaps carry_texture(const ImageGrid& grid, const TextureMaps& reference,
                          const std::vector<float>& def_to_ref);

} // namespace phantasm
