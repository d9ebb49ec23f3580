// The signed (rotation-variant) SVD of a 3x3 deformation gradient, warm-started from the last
// rotation: the core of every tet projection in the local step.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace phantasm {

/// The rotation-variant SVD of a 3x3 matrix: F = U diag(sigma) V^T with U and V rotations
/// (determinant +1), so an inverted F (det < 0) has exactly one negative singular value, the
/// one of smallest magnitude. U is the rotation closest to F over SO(3).
struct SignedSvd {
  Eigen::Matrix3d U;
  Eigen::Matrix3d V;
  Eigen::Vector3d sigma;
};

/// Computes the signed SVD without a general iterative SVD: the rotation R = U V^T by a
/// quaternion iteration (Newton steps on the symmetry of R^T F, Mueller et al. 2016's step
/// where Newton's is not defined), warm-started from `rotation` and written back to it, then the
/// eigen-decomposition of the symmetric R^T F by Jacobi sweeps. A solver that keeps one quaternion per
/// element needs one or two iterations per call once motion is smooth.
/// @param max_iterations of the rotation iteration (it stops earlier when the update is below
///        1e-15 radians)
SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, int max_iterations = 40);

/// As above, with the eigenvectors V warm-started too (cyclic Jacobi sweeps from the last V:
/// one sweep once motion is smooth) and written back.
SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, Eigen::Quaterniond& eigenvectors,
                     int max_iterations = 40);

/// The last step of the rotation's search: at the optimum rotation R (with R^T F = V
/// diag(lambda) V^T) no two eigenvalues sum to a negative number, but a stationary point of the
/// iteration can miss that (e.g. a start 180 degrees away). Flipping the signs of two
/// eigenvalues is a half turn of R about the third eigenvector and raises tr(R^T F) whenever it
/// makes their sum larger: done until no pair sums below zero. Returns whether R turned.
bool turn_to_positive_pairs(Eigen::Matrix3d& R, const Eigen::Matrix3d& V, Eigen::Vector3d& lambda);

} // namespace phantasm
