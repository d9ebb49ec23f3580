#include "sim/signed_svd.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <utility>

namespace phantasm {
namespace {

/// Rotates R = rotation until R^T F is symmetric. With S = R^T F, a = vee(S - S^T) and the
/// body-frame update R <- R exp(hat(w)), symmetry to first order needs (tr S I - sym S) w = a:
/// Newton's step, quadratic near the optimum, where that matrix is positive definite (its
/// eigenvalues are the pairwise sums of singular values). Elsewhere Mueller et al. (2016)'s step
/// w = a / |tr S| is taken, which always makes progress.
void align_rotation(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, int max_iterations) {
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    const Eigen::Matrix3d S = rotation.toRotationMatrix().transpose() * F;
    const Eigen::Vector3d a(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1));
    const double trace = S.trace();
    const double scale = std::abs(trace) + S.cwiseAbs().maxCoeff();
    if (!(a.norm() > 1e-15 * scale)) break; // converged (also stops on NaN)
    const Eigen::Matrix3d M = trace * Eigen::Matrix3d::Identity() - 0.5 * (S + S.transpose());
    const Eigen::LLT<Eigen::Matrix3d> newton(M);
    const bool use_newton = newton.info() == Eigen::Success && M.diagonal().minCoeff() > 1e-6 * scale;
    const Eigen::Vector3d w =
        use_newton ? Eigen::Vector3d(newton.solve(a)) : Eigen::Vector3d(a / (std::abs(trace) + 1e-300));
    const double angle = w.norm();
    if (!(angle > 1e-300)) break;
    if (angle < 1e-4) {
      // Small angle: q(w) = (1, w/2) to third order, no trigonometry.
      rotation = rotation * Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z());
    } else {
      rotation = rotation * Eigen::Quaterniond(Eigen::AngleAxisd(std::min(angle, 1.0), w / angle));
    }
    rotation.normalize();
    // A Newton step this small leaves an error of its square: below what the solvers resolve.
    if (use_newton && angle < 1e-7) break;
  }
}

/// Cyclic Jacobi sweeps on a symmetric matrix, starting from the eigenvectors V (a warm start:
/// one sweep suffices when V is close). On return S = V diag(lambda) V^T. Rotations update only
/// the entries they touch (Numerical Recipes' formulation).
void jacobi_eigen(const Eigen::Matrix3d& S, Eigen::Matrix3d& V, Eigen::Vector3d& lambda) {
  Eigen::Matrix3d A = V.transpose() * S * V;
  const double norm = S.cwiseAbs().maxCoeff() + 1e-300;
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = std::abs(A(0, 1)) + std::abs(A(0, 2)) + std::abs(A(1, 2));
    if (!(off > 1e-15 * norm)) break;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        const double apq = A(p, q);
        if (apq == 0.0) continue;
        const int r = 3 - p - q;
        const double theta = (A(q, q) - A(p, p)) / (2.0 * apq);
        const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        A(p, p) -= t * apq;
        A(q, q) += t * apq;
        A(p, q) = A(q, p) = 0.0;
        const double arp = A(r, p), arq = A(r, q);
        A(r, p) = A(p, r) = c * arp - s * arq;
        A(r, q) = A(q, r) = s * arp + c * arq;
        const Eigen::Vector3d vp = V.col(p), vq = V.col(q);
        V.col(p) = c * vp - s * vq;
        V.col(q) = s * vp + c * vq;
      }
    }
  }
  lambda = A.diagonal();
}

} // namespace

SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, int max_iterations) {
  Eigen::Quaterniond eigenvectors = Eigen::Quaterniond::Identity();
  return signed_svd(F, rotation, eigenvectors, max_iterations);
}

SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, Eigen::Quaterniond& eigenvectors,
                     int max_iterations) {
  align_rotation(F, rotation, max_iterations);
  Eigen::Matrix3d R = rotation.toRotationMatrix();
  Eigen::Matrix3d S = R.transpose() * F;
  S = 0.5 * (S + S.transpose()).eval();
  Eigen::Matrix3d V = eigenvectors.toRotationMatrix();
  Eigen::Vector3d lambda;
  jacobi_eigen(S, V, lambda);
  bool flipped = false;
  // At the optimum rotation at most one eigenvalue is negative, and it is the one of smallest
  // magnitude. A stationary point of the iteration can miss that (e.g. a start 180 degrees
  // away): flipping the signs of two eigenvalues is a 180-degree turn of R about the third
  // eigenvector, and raises tr(R^T F) whenever it makes the sum of the two larger.
  for (bool changed = true; changed;) {
    changed = false;
    for (int a = 0; a < 3 && !changed; ++a) {
      for (int b = a + 1; b < 3 && !changed; ++b) {
        if (lambda[a] + lambda[b] < 0.0) {
          Eigen::Vector3d flip = Eigen::Vector3d::Ones();
          flip[a] = flip[b] = -1.0;
          R = R * V * flip.asDiagonal() * V.transpose();
          lambda[a] = -lambda[a];
          lambda[b] = -lambda[b];
          changed = true;
          flipped = true;
        }
      }
    }
  }
  // Order by decreasing value (the negative one, if any, last); V stays a rotation.
  SignedSvd svd;
  int order[3] = {0, 1, 2};
  if (lambda[order[0]] < lambda[order[1]]) std::swap(order[0], order[1]);
  if (lambda[order[1]] < lambda[order[2]]) std::swap(order[1], order[2]);
  if (lambda[order[0]] < lambda[order[1]]) std::swap(order[0], order[1]);
  for (int k = 0; k < 3; ++k) {
    svd.sigma[k] = lambda[order[k]];
    svd.V.col(k) = V.col(order[k]);
  }
  if (svd.V.determinant() < 0.0) svd.V.col(2) = -svd.V.col(2);
  svd.U = R * svd.V;
  if (flipped) rotation = Eigen::Quaterniond(R).normalized();
  eigenvectors = Eigen::Quaterniond(svd.V).normalized();
  return svd;
}

} // namespace phantasm
