// The MR stage's plan: the images it will make for a scene, the tissue values used and the
// acquisition effects asked for.
#pragma once

#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "mri/mri_settings.hpp"

namespace phantasm {

/// What the MR stage will make: one image per sequence and state, the tissue values used for the
/// organs' tissues, and the acquisition effects the settings ask for (k-space, bias, coils, noise).
StageReport plan_mri(const MriSettings& settings, const OrganTable& organs);

} // namespace phantasm
