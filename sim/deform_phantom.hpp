#pragma once

#include "anatomy/phantom.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "scene/scene.hpp"
#include "sim/solve_report.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace phantasm {

/// A piece of the phantom the solver moved: the tet mesh of a simulated organ whose container
/// does not move, with the organs nested in it embedded (they follow its tets barycentrically).
struct DeformedBody {
  std::string organ;
  Eigen::MatrixX3d rest_mm;
  Eigen::MatrixX3d deformed_mm;
  Eigen::MatrixX4i tets;
};

/// Where every organ's vertices went.
struct OrganDeformation {
  std::string organ;
  std::string moved_by;        ///< "solver" (a body), "embedded in <organ>", "fixed", "rigid"
  Eigen::MatrixX3d surface_mm; ///< patch base vertices, or sheet vertices
  Eigen::MatrixX3d solid_mm;   ///< tet vertices (solid organs)
};

struct PhantomDeformation {
  std::vector<OrganDeformation> organs; ///< scene order
  std::vector<DeformedBody> bodies;
  std::vector<SolveReport> solves;      ///< one per frame
  double attachment_error_mm = 0.0;     ///< largest distance of a pushed point from its target
  double obstacle_penetration_mm = 0.0; ///< deepest free vertex inside an obstacle
};

/// Deforms the phantom as the scene says (METHOD.md sections 2-3) [choices documented in
/// docs/deformation.md]: each simulated organ whose container does not move becomes a body
/// (its tet mesh; each tet takes the material of the innermost organ holding its centroid);
/// organs nested in a body are embedded in its tets; a body inside a fixed or unmoving organ
/// has its boundary held there. Gravity acts on the bodies' masses; a displacement load pulls
/// the organ's surface points in its region to their displaced places by stiff springs.
/// Quasi-static mode solves for equilibrium once; dynamic mode steps `frames` times and keeps
/// the last frame. What was modelled goes into `report`.
/// @throws InputError when a body is held by nothing in quasi-static mode, or the scene asks
/// for a solver this version does not have
PhantomDeformation deform_phantom(const Scene& scene, const Phantom& phantom, StageReport& report,
                                  Reporter& reporter);

/// The phantom with every organ moved to its deformed place (patches follow their base).
Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation);

} // namespace phantasm
