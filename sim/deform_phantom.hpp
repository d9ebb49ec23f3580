#pragma once

#include "anatomy/phantom.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "scene/scene.hpp"
#include "sim/phantom_deformation.hpp"

namespace phantasm {

/// Deforms the phantom as the scene says (docs/method.md sections 2-3) [choices documented in
/// docs/deformation.md]: each simulated organ whose container does not move becomes a body
/// (its tet mesh; each tet takes the material of the innermost organ holding its centroid);
/// organs nested in a body are embedded in its tets; a body inside a fixed or unmoving organ
/// has its boundary held there. Gravity acts on the bodies' masses; a displacement load pulls
/// the organ's surface points in its region to their displaced places by stiff springs.
/// Quasi-static mode solves for equilibrium (in `load_steps` increments); dynamic mode steps
/// `frames` times and keeps the last frame. What was modelled goes into `report`.
/// @throws InputError when a body is held by nothing in quasi-static mode, a position-based
/// solver (xpbd, gauss_seidel_pbd) is asked for in quasi-static mode, a material is not
/// defined, an enclosed volume is asked of an open sheet, an organ of a collision pair is not a
/// body of its own with a closed surface, or a solve goes non-finite
PhantomDeformation deform_phantom(const Scene& scene, const Phantom& phantom, StageReport& report,
                                  Reporter& reporter);

/// The phantom with every organ moved to its deformed place (patches follow their base).
Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation);

} // namespace phantasm
