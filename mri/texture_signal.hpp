// Texture in the MR stage: the signal of a textured tissue at a voxel's T1 and PD factors, and
// the parameter maps with the factors applied (voxelize/material_maps.hpp makes the factors).
#pragma once

#include "mri/mr_images.hpp"
#include "mri/mri_settings.hpp"
#include "mri/sequence_type.hpp"
#include "mri/tissue_parameters.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// Per tissue of a phantom, its signal in one sequence as a function of a factor of its T1
/// (tabulated on a logarithmic grid of factors, linear between), for textured tissues only.
class TexturedSignal {
public:
  /// @param tissues the phantom's tissue list; @param maps the state's texture
  /// @param relaxation the tissues' relaxation (as the untextured signal reads it)
  /// @param gain the receiver gain the untextured signals carry
  TexturedSignal(const SequenceSettings& sequence, const std::vector<std::string>& tissues,
                 const std::vector<Relaxation>& relaxation, double gain, const TextureMaps& maps);

  const TextureMaps& maps() const { return *m_maps; }
  bool textured(std::size_t tissue) const { return !m_table[tissue].empty(); }
  /// The signal (scanner units) of `tissue` with T1 times t1_factor and PD times pd_factor.
  double signal(std::size_t tissue, float t1_factor, float pd_factor) const;

private:
  const TextureMaps* m_maps;
  std::vector<std::vector<double>> m_table; ///< per tissue; empty: not textured
};

/// A T1 gain matched to a sequence (texture.match): with T1 x exp(-gain d) and PD x
/// exp(PD_gain d), the sequence's signal (its magnitude, as images take it) changes by the
/// relative amount d, to first order, so that a texture d measured on a scan of that contrast
/// gives the image the scan's variation.
struct MatchedT1Gain {
  double gain = 0.0;
  double sensitivity = 0.0; ///< s = -d ln|S| / d ln T1 at the tissue's relaxation
  bool clamped = false;     ///< |(1 - PD_gain) / s| exceeded the largest gain: the gain is that
};

/// gain = (1 - PD_gain) / s, s by a central difference in ln T1 (step 1e-4), within +-max_gain
/// (the sign of the ratio kept: negative where a longer T1 brightens, as near an inversion's
/// null). Empty when the tissue has no signal in the sequence.
std::optional<MatchedT1Gain> matched_T1_gain(const SequenceSettings& sequence, const Relaxation& tissue,
                                             double PD_gain, double max_gain = 5.0);

/// Multiplies, per voxel, each textured tissue's T1 and PD by the texture's factors and mixes the
/// maps again as parameter_maps() does (PD summed, T1 averaged over the tissues that have one).
void apply_texture(ParameterMaps& maps, const TissueVolumes& volumes, const std::vector<std::string>& tissues,
                   const std::map<std::string, TissueParameters>& parameters, const TextureMaps& texture);

} // namespace phantasm
