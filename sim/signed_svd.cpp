#include "sim/signed_svd.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <utility>

namespace phantasm {
namespace {

/// Rotates R = rotation until R^T F is symmetric. With S = R^T F, a = vee(S - S^T) and the
/// body-frame update R <- R exp(hat(w)), symmetry to first order needs (tr S I - sym S) w = a:
/// Newton's step, quadratic near the optimum, where that matrix is positive definite (its
/// eigenvalues are the pairwise sums of singular values). Elsewhere Mueller et al. (2016)'s step
/// w = a / |tr S| is taken, which always makes progress. On return R is the rotation's matrix
/// and S = R^T F.
void align_rotation(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, int max_iterations,
                    Eigen::Matrix3d& R, Eigen::Matrix3d& S) {
  R = rotation.toRotationMatrix();
  S.noalias() = R.transpose() * F;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    const Eigen::Vector3d a(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1));
    const double trace = S.trace();
    const double scale = std::abs(trace) + S.cwiseAbs().maxCoeff();
    if (!(a.squaredNorm() > 1e-30 * scale * scale)) break; // converged (also stops on NaN)
    // M = tr S I - sym S, solved by its adjugate (symmetric 3x3): positive definite when its
    // leading minors are.
    const double m00 = trace - S(0, 0), m11 = trace - S(1, 1), m22 = trace - S(2, 2);
    const double m01 = -0.5 * (S(0, 1) + S(1, 0)), m02 = -0.5 * (S(0, 2) + S(2, 0)),
                 m12 = -0.5 * (S(1, 2) + S(2, 1));
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11;
    const double determinant = m00 * c00 + m01 * c01 + m02 * c02;
    const double floor = 1e-6 * scale;
    const bool use_newton = m00 > floor && m11 > floor && m22 > floor &&
                            m00 * m11 - m01 * m01 > floor * floor && determinant > floor * floor * floor;
    Eigen::Vector3d w;
    if (use_newton) {
      const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12, c22 = m00 * m11 - m01 * m01;
      w = Eigen::Vector3d(c00 * a[0] + c01 * a[1] + c02 * a[2], c01 * a[0] + c11 * a[1] + c12 * a[2],
                          c02 * a[0] + c12 * a[1] + c22 * a[2]) /
          determinant;
    } else {
      w = a / (std::abs(trace) + 1e-300);
    }
    const double angle = w.norm();
    if (!(angle > 1e-300)) break;
    if (angle < 1e-2) {
      // Small angle: the normalized (1, w/2) turns by 2 atan(|w|/2), |w| to third order: no
      // trigonometry, and the next iteration absorbs the difference.
      rotation = rotation * Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z());
    } else {
      rotation = rotation * Eigen::Quaterniond(Eigen::AngleAxisd(std::min(angle, 1.0), w / angle));
    }
    rotation.normalize();
    R = rotation.toRotationMatrix();
    S.noalias() = R.transpose() * F;
    // After a Newton step this small, what is left is of the order of its square: far below
    // what the projections resolve.
    if (use_newton && angle < 1e-7) break;
  }
}

/// Cyclic Jacobi sweeps on a symmetric matrix, starting from the eigenvectors V (a warm start:
/// one sweep suffices when V is close and the values are apart; nearly equal values, as in
/// nearly rigid tets, take two or three). On return S = V diag(lambda) V^T to 1e-12 of |S|:
/// projections built from it are that accurate, their energies to 1e-24. Rotations update
/// only the entries they touch (Numerical Recipes' formulation); negligible ones are skipped.
void jacobi_eigen(const Eigen::Matrix3d& S, Eigen::Matrix3d& V, Eigen::Vector3d& lambda) {
  Eigen::Matrix3d A = V.transpose() * S * V;
  const double norm = S.cwiseAbs().maxCoeff() + 1e-300;
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = std::abs(A(0, 1)) + std::abs(A(0, 2)) + std::abs(A(1, 2));
    if (!(off > 1e-12 * norm)) break;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        const double apq = A(p, q);
        if (std::abs(apq) <= 1e-14 * norm) continue;
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

bool turn_to_positive_pairs(Eigen::Matrix3d& R, const Eigen::Matrix3d& V, Eigen::Vector3d& lambda) {
  bool turned = false;
  for (bool changed = true; changed;) {
    changed = false;
    for (int a = 0; a < 3 && !changed; ++a) {
      for (int b = a + 1; b < 3 && !changed; ++b) {
        if (lambda[a] + lambda[b] < 0.0) {
          Eigen::Vector3d flip = Eigen::Vector3d::Ones();
          flip[a] = flip[b] = -1.0;
          R = (R * V * flip.asDiagonal() * V.transpose()).eval();
          lambda[a] = -lambda[a];
          lambda[b] = -lambda[b];
          changed = true;
          turned = true;
        }
      }
    }
  }
  return turned;
}

SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, int max_iterations) {
  Eigen::Quaterniond eigenvectors = Eigen::Quaterniond::Identity();
  return signed_svd(F, rotation, eigenvectors, max_iterations);
}

SignedSvd signed_svd(const Eigen::Matrix3d& F, Eigen::Quaterniond& rotation, Eigen::Quaterniond& eigenvectors,
                     int max_iterations) {
  Eigen::Matrix3d R, S;
  align_rotation(F, rotation, max_iterations, R, S);
  S = 0.5 * (S + S.transpose()).eval();
  Eigen::Matrix3d V = eigenvectors.toRotationMatrix();
  Eigen::Vector3d lambda;
  jacobi_eigen(S, V, lambda);
  const bool flipped = turn_to_positive_pairs(R, V, lambda);
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
