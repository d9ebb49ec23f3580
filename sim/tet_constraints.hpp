// The strain and volume constraint sets of tet elements on the deformation gradient's signed
// singular values, and their projections.
#pragma once

#include "sim/signed_svd.hpp"

#include <Eigen/Core>

namespace phantasm {

/// The constraint sets of tet elements, in terms of the deformation gradient's signed singular
/// values (docs/method.md sections 3.3-3.4). Both keep U and V and change only the singular values.
struct SingularValueRange {
  double min = 1.0;
  double max = 1.0;
};

/// Tet strain: each singular value clamped to [min, max]. min = max = 1 is as-rigid-as-possible;
/// a negative singular value (an inverted tet) goes to min, so the target is never inverted.
Eigen::Vector3d project_strain(const Eigen::Vector3d& sigma, const SingularValueRange& range);

/// Tet volume: the point closest to sigma whose product (the volume ratio det F) lies in
/// [min, max], from the one-dimensional equation of its Lagrange multiplier (safeguarded
/// Newton, to machine precision). Inverted tets (product < 0) are brought to min on the branch
/// of positive values.
Eigen::Vector3d project_volume(const Eigen::Vector3d& sigma, const SingularValueRange& range);

/// Triangle area: the same for the two singular values of a triangle's 3x2 deformation
/// gradient (their product, the area ratio, clamped to [min, max]).
Eigen::Vector2d project_area(const Eigen::Vector2d& sigma, const SingularValueRange& range);

/// Which set a tet constraint projects onto.
enum class TetConstraintKind { strain, volume };

/// Value, sigma-space gradient and sigma-space Hessian of Psi(sigma) = w/2 |sigma - P(sigma)|^2.
struct SingularValueEnergy {
  double value = 0.0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero(); ///< w (sigma - P(sigma)), by the envelope theorem
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};

/// @param with_hessian false: the value and gradient only, the Hessian left zero (the volume
///        set's Hessian takes six more projections, by central differences: most of the cost of an
///        energy or gradient evaluation, which never reads it)
SingularValueEnergy singular_value_energy(TetConstraintKind kind, const SingularValueRange& range,
                                          double weight, const Eigen::Vector3d& sigma,
                                          bool with_hessian = true);

/// The 9x9 Hessian of an isotropic energy with respect to vec(F) (column-major), made positive
/// semi-definite by clamping its eigenvalues at 0: the closed-form eigensystem of isotropic
/// energies (scaling modes from the sigma-space Hessian; for each pair of singular values a
/// twist mode (psi_i + psi_j) / (sigma_i + sigma_j) and a flip mode (psi_i - psi_j) /
/// (sigma_i - sigma_j)). With clamp_negative false: the exact Hessian (for tests).
Eigen::Matrix<double, 9, 9> projected_hessian(const SignedSvd& svd, const SingularValueEnergy& energy,
                                              bool clamp_negative = true);

} // namespace phantasm
