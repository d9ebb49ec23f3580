// The deformation stage's result: the bodies the solver moved and where every organ's
// vertices went, which the voxelizer and the writers read.
#pragma once

#include "sim/solve_report.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

// The deformation stage's result types, apart from the solver (sim/deform_phantom.hpp), so that
// the voxelizer and the writers include only what they read.

namespace phantasm {

/// A piece of the phantom the solver moved: the tet mesh of a simulated organ whose container
/// does not move, with the organs nested in it embedded (they follow its tets barycentrically).
struct DeformedBody {
  std::string organ;
  Eigen::MatrixX3d rest_mm;
  Eigen::MatrixX3d deformed_mm;
  Eigen::MatrixX4i tets;
  double smallest_det_F = 1.0; ///< the smallest det F (deformed over rest volume) of its tets
  long inverted_tets = 0;      ///< tets with det F <= 0 (turned inside out)
  /// For each tet, det F (deformed over rest volume; NaN for a tet of no rest volume)
  std::vector<double> det_F;
  /// For each tet, the organ whose material it takes, as its index in the scene's organ table
  /// (the organ's dseg label minus one): the body's organ or one nested in it.
  std::vector<int> tet_organ;
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

} // namespace phantasm
