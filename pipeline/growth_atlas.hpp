// The atlas a scene's growth loads name (`{type: growth, region: ..., atlas: aal}`), read once
// per run before the anatomy is built, so that a region the atlas lacks stops the run at once.
#pragma once

#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/sim_settings.hpp"

namespace phantasm {

/// The deformation settings a run solves: the scene's, with the atlas its growth loads name
/// (DeformationSettings::region_atlas) read and their regions resolved. What was read, from
/// which files, goes into `report` (the deformation stage's) and the log. Unchanged when no
/// growth load names regions.
/// @throws SettingError naming the load's region for a region the atlas lacks or one prescribed
///   twice; InputError when the atlas's files are missing
DeformationSettings with_growth_atlas(const DeformationSettings& deformation, StageReport& report,
                                      Reporter& reporter);

} // namespace phantasm
