#pragma once

#include "core/stage_report.hpp"
#include "scene/scene.hpp"

namespace phantasm {

/// What the MR stage will make: one image per sequence and state, the tissue values used, and
/// the acquisition effects the scene asks for (k-space, bias, coils, noise).
StageReport plan_mri(const Scene& scene);

} // namespace phantasm
