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

/// The homogeneous growth of the whole head that follows the solve (deformation.head_scale): y =
/// center + factors * (x - center), per axis. The identity leaves every position's bits as they are.
struct HeadAffine {
  Eigen::Vector3d factors = Eigen::Vector3d::Ones();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();

  bool identity() const { return (factors.array() == 1.0).all(); }
  /// det A: the change of every volume.
  double determinant() const { return factors.prod(); }
  /// The grown position of a point of the solved (regional) state.
  Eigen::Vector3d apply(const Eigen::Vector3d& x) const {
    return identity() ? x : Eigen::Vector3d(center + factors.cwiseProduct(x - center));
  }
  /// Its inverse: the solved (regional) position of a grown point.
  Eigen::Vector3d unapply(const Eigen::Vector3d& y) const {
    return identity() ? y : Eigen::Vector3d(center + (y - center).cwiseQuotient(factors));
  }
  /// Every row of `points` grown in place.
  void apply_rows(Eigen::MatrixX3d& points) const {
    if (identity()) return;
    for (Eigen::Index r = 0; r < points.rows(); ++r)
      points.row(r) = apply(points.row(r).transpose()).transpose();
  }
};

struct PhantomDeformation {
  std::vector<OrganDeformation> organs; ///< scene order
  std::vector<DeformedBody> bodies;
  std::vector<SolveReport> solves;      ///< one per frame
  double attachment_error_mm = 0.0;     ///< largest distance of a pushed point from its target
  double obstacle_penetration_mm = 0.0; ///< deepest free vertex inside an obstacle
  /// The growth of the whole head applied after the solve (deformation.head_scale): already in
  /// every deformed position above (organs and bodies); the solve's own state is its inverse.
  HeadAffine head;
};

} // namespace phantasm
