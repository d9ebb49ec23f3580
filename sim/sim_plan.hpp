// The deformation stage's plan: what the stage will solve for a scene and what it leaves out
// (how each organ moves, classify_organ_motion(), is in sim/sim_settings.hpp).
#pragma once

#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "sim/sim_settings.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// What the deformation stage will solve: which organs, which loads, which solver and its stop
/// criteria; and what it leaves out (organs nothing moves, the whole stage for mode none).
/// @param deformation the deformation settings, with the organs' materials and mechanics
/// @param organs the organ table (names and nesting)
StageReport plan_sim(const DeformationSettings& deformation, const OrganTable& organs);

} // namespace phantasm
