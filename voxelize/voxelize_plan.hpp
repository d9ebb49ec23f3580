// The voxelization stage's plan: which organs lie in the field of view and what volumes the
// stage will make.
#pragma once

#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "voxelize/voxelize_settings.hpp"

#include <optional>

namespace phantasm {

/// True unless an organ's bounds lie wholly outside the grid's field of view (an organ whose
/// bounds are known only from its file counts as inside until it is read).
/// @param bounds the organ's shape bounds in RAS mm (VoxelizationSettings::organ_bounds_mm)
bool organ_in_field_of_view(const std::optional<WorldBox>& bounds, const ImageGrid& grid);

/// What the voxelization stage will make: the grid, the organs it voxelizes (those in the field
/// of view), and the derived volumes the outputs ask for.
StageReport plan_voxelize(const VoxelizationSettings& settings, const OrganTable& organs,
                          const GridSettings& grid);

} // namespace phantasm
