// The anatomy stage's plan: what it will build for a scene, the analytic bounds of shapes and
// organs' nesting depth, which the pipeline's plan and the voxelizer's field-of-view test read.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "core/organ_table.hpp"
#include "core/stage_report.hpp"

namespace phantasm {

/// What the anatomy stage will build: one patch surface per organ, a tet mesh for each solid
/// organ, and the nesting (from the organ table) that decides which tissue fills a point.
StageReport plan_anatomy(const AnatomySettings& anatomy, const OrganTable& organs);

} // namespace phantasm
