#pragma once

#include "core/stage_report.hpp"
#include "scene/scene.hpp"

namespace phantasm {

/// True unless the organ's analytic bounds lie wholly outside the scene's field of view (an
/// organ whose bounds are known only from its file counts as inside until it is read).
bool organ_in_field_of_view(const Scene& scene, const OrganSettings& organ);

/// What the voxelization stage will make: the grid, the organs it voxelizes (those in the field
/// of view), and the derived volumes the outputs ask for.
StageReport plan_voxelize(const Scene& scene);

} // namespace phantasm
