// The deformation stage's plan: how each organ moves (simulated, fixed, rigid) and what the
// stage will solve for a scene and what it leaves out.
#pragma once

#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "sim/sim_settings.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// How the deformation stage treats each organ.
enum class OrganMotion {
  simulated, ///< a load acts on it: its vertices are solved for
  fixed,     ///< held in place by the scene (an attachment)
  rigid,     ///< nothing moves it: carried along rigidly, not simulated
};

/// The motion class of every organ of the table, in its order. With no deformation every organ
/// is rigid.
std::vector<OrganMotion> classify_organ_motion(const DeformationSettings& deformation,
                                               const OrganTable& organs);

/// What the deformation stage will solve: which organs, which loads, which solver and its stop
/// criteria; and what it leaves out (organs nothing moves, the whole stage for mode none).
/// @param deformation the deformation settings, with the organs' materials and mechanics
/// @param organs the organ table (names and nesting)
StageReport plan_sim(const DeformationSettings& deformation, const OrganTable& organs);

} // namespace phantasm
