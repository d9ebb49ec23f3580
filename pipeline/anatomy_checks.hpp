// Checks of a scene that need its built anatomy: the sizes of organs read from files against
// their containers, and where the obstacles are at rest.
#pragma once

#include "anatomy/organ.hpp"
#include "scene/scene.hpp"

namespace phantasm {

/// Refuses an organ larger than its container along an axis (by more than 5 %: surfaces of seeded
/// variation may differ a little from their shapes), and an organ that lies wholly inside the
/// obstacles at rest (no simulated vertex may enter an obstacle: such an organ could only be
/// thrown out of it).
/// @throws SettingError naming the organ's `inside` or the obstacle
void check_built_anatomy(const Scene& scene, const Phantom& phantom);

} // namespace phantasm
