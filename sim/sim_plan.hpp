#pragma once

#include "core/stage_report.hpp"
#include "scene/scene.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// How the deformation stage treats each organ.
enum class OrganMotion {
  simulated, ///< a load acts on it: its vertices are solved for
  fixed,     ///< held in place by the scene (an attachment)
  rigid,     ///< nothing moves it: carried along rigidly, not simulated
};

/// The motion class of every organ, in scene order. With no deformation every organ is rigid.
std::vector<OrganMotion> classify_organ_motion(const Scene& scene);

/// What the deformation stage will solve: which organs, which loads, which solver and its stop
/// criteria; and what it leaves out (organs nothing moves, the whole stage for mode none).
StageReport plan_sim(const Scene& scene);

} // namespace phantasm
