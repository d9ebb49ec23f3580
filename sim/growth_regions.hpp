// The atlas regions growth loads name (`{type: growth, region: [...], atlas: aal}`), resolved
// to the atlas's labels: what a run checks before any work, and what the deformation grows.
#pragma once

#include "sim/sim_settings.hpp"

#include <cstdint>
#include <vector>

namespace phantasm {

/// Per load of `deformation` (in its order), the labels of the regions a growth load names
/// (each name a region of deformation.region_atlas or a group of them); empty for other loads
/// and for the growth of an organ.
/// @throws SettingError (deformation.loads[k].region) for a region or group the atlas does not
///   have (listing its close names), a region prescribed by two loads, or region growth with
///   no atlas read for it
std::vector<std::vector<std::int32_t>> growth_region_labels(const DeformationSettings& deformation);

} // namespace phantasm
