#pragma once

#include "mri/tissue_parameters.hpp"
#include "voxelize/tissue_volumes.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// Ground-truth quantitative maps of one state on the grid. PD adds up over a voxel's tissues
/// (fraction-weighted sum); T1, T2 and T2* are the fraction-weighted means over the tissues of
/// the voxel that have the value (0 where none has it, e.g. background).
struct ParameterMaps {
  std::vector<float> PD, T1_ms, T2_ms, T2star_ms;
};

/// The maps of `volumes`, whose fractions follow the order of `tissues`.
ParameterMaps parameter_maps(const TissueVolumes& volumes, const std::vector<std::string>& tissues,
                             const std::map<std::string, TissueParameters>& parameters);

} // namespace phantasm
