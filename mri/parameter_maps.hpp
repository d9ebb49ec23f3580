// Ground-truth quantitative maps (PD, T1, T2, T2*) of a state from its tissue fractions and
// the tissues' parameters.
#pragma once

#include "mri/mr_images.hpp"
#include "mri/tissue_parameters.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <map>
#include <string>
#include <vector>

namespace phantasm {

/// The maps of `volumes`, whose fractions follow the order of `tissues`.
ParameterMaps parameter_maps(const TissueVolumes& volumes, const std::vector<std::string>& tissues,
                             const std::map<std::string, TissueParameters>& parameters);

} // namespace phantasm
