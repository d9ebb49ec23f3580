#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "core/organ_table.hpp"
#include "core/stage_report.hpp"

namespace phantasm {

/// What the anatomy stage will build: one patch surface per organ, a tet mesh for each solid
/// organ, and the nesting (from the organ table) that decides which tissue fills a point.
StageReport plan_anatomy(const AnatomySettings& anatomy, const OrganTable& organs);

} // namespace phantasm
