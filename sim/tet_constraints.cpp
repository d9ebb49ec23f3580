#include "sim/tet_constraints.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace phantasm {

Eigen::Vector3d project_strain(const Eigen::Vector3d& sigma, const SingularValueRange& range) {
  return sigma.cwiseMax(range.min).cwiseMin(range.max);
}

namespace {

/// Root of an increasing function on [lo, hi] (f(lo) < 0 < f(hi)) by Newton steps kept inside
/// the shrinking bracket, bisection where Newton's step leaves it.
template <typename Function>
double bracketed_root(Function&& f, double lo, double hi, double start) {
  double x = start;
  for (int iteration = 0; iteration < 200; ++iteration) {
    double slope = 0.0;
    const double value = f(x, &slope);
    if (std::abs(value) < 1e-14) return x;
    (value < 0.0 ? lo : hi) = x;
    if (hi - lo <= 1e-15 * std::max(std::abs(lo), std::abs(hi))) return x;
    double next = slope > 0.0 && std::isfinite(value) ? x - value / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    x = next;
  }
  return x;
}

/// The multiplier of the linearized problem, s_i = sigma_i + lambda P / sigma_i: a start from
/// which Newton needs one or two steps for the small changes of a running solve.
template <int N>
double linear_start(const Eigen::Matrix<double, N, 1>& sigma, double product, double P) {
  if (!(product > 0.0)) return 0.0;
  const double curvature = P * sigma.cwiseAbs2().cwiseInverse().sum();
  return curvature > 0.0 && std::isfinite(curvature) ? (std::log(P) - std::log(product)) / curvature : 0.0;
}

/// The closest point to sigma whose product lies in [min, max] (N = 3: tet volume, N = 2:
/// triangle area).
template <int N>
Eigen::Matrix<double, N, 1> project_product(const Eigen::Matrix<double, N, 1>& sigma,
                                            const SingularValueRange& range) {
  using Vector = Eigen::Matrix<double, N, 1>;
  const double product = sigma.prod();
  if (product >= range.min && product <= range.max) return sigma;
  const double P = product < range.min ? range.min : range.max;
  // The closest point s with prod(s) = P satisfies s_i - sigma_i = lambda P / s_i, so each
  // s_i(lambda) = (sigma_i +- sqrt(sigma_i^2 + 4 lambda P)) / 2. The multiplier solves
  // prod s_i(lambda) = P.
  // `minus` selects the other root for one coordinate (see the shrinking case below).
  int minus = -1;
  auto s_of = [&](double lambda, Vector* ds) {
    Vector s;
    for (int i = 0; i < N; ++i) {
      const double root = std::sqrt(std::max(0.0, sigma[i] * sigma[i] + 4.0 * lambda * P));
      const double sign = i == minus ? -1.0 : 1.0;
      s[i] = 0.5 * (sigma[i] + sign * root);
      if (ds) (*ds)[i] = root > 0.0 ? sign * P / root : 0.0;
    }
    return s;
  };
  // prod s(lambda) / P - 1: increasing in lambda on the branches used, and free of logarithms.
  auto g = [&](double lambda, double* slope) {
    Vector ds;
    const Vector s = s_of(lambda, &ds);
    const double ratio = s.prod() / P;
    *slope = ratio * ds.cwiseQuotient(s).sum();
    return ratio - 1.0;
  };
  if (product < P) {
    // Growing (also inverted tets, whose negative value starts at 0): lambda > 0, g increases
    // from g(0) < 0 without bound.
    double hi = 1.0;
    double unused = 0.0;
    while (g(hi, &unused) < 0.0)
      hi *= 2.0;
    return s_of(bracketed_root(g, 0.0, hi, linear_start<N>(sigma, product, P)), nullptr);
  }
  // Shrinking (all values positive): lambda in [lo, 0] with lo = -min sigma^2 / 4P, where the
  // smallest value's two roots meet. If even g(lo) > 0, the closest point takes the smaller root
  // for that smallest value: continue past lo on its other branch, where g falls to -inf as
  // lambda returns to 0.
  int smallest = 0;
  sigma.minCoeff(&smallest);
  const double lo = -sigma[smallest] * sigma[smallest] / (4.0 * P);
  double unused = 0.0;
  if (g(lo, &unused) <= 0.0)
    return s_of(bracketed_root(g, lo, 0.0, linear_start<N>(sigma, product, P)), nullptr);
  minus = smallest;
  auto falling = [&](double lambda, double* slope) {
    const double value = g(lambda, slope);
    *slope = 0.0; // not monotone in general: bisection only
    return -value;
  };
  return s_of(bracketed_root(falling, lo, 0.0, 0.5 * lo), nullptr);
}

} // namespace

Eigen::Vector3d project_volume(const Eigen::Vector3d& sigma, const SingularValueRange& range) {
  return project_product<3>(sigma, range);
}

Eigen::Vector2d project_area(const Eigen::Vector2d& sigma, const SingularValueRange& range) {
  return project_product<2>(sigma, range);
}

SingularValueEnergy singular_value_energy(TetConstraintKind kind, const SingularValueRange& range,
                                          double weight, const Eigen::Vector3d& sigma, bool with_hessian) {
  auto project = [&](const Eigen::Vector3d& x) {
    return kind == TetConstraintKind::strain ? project_strain(x, range) : project_volume(x, range);
  };
  SingularValueEnergy e;
  const Eigen::Vector3d d = sigma - project(sigma);
  e.value = 0.5 * weight * d.squaredNorm();
  e.gradient = weight * d;
  if (!with_hessian) return e;
  if (kind == TetConstraintKind::strain) {
    for (int k = 0; k < 3; ++k)
      e.hessian(k, k) = (sigma[k] < range.min || sigma[k] > range.max) ? weight : 0.0;
  } else if (d.squaredNorm() > 0.0) {
    // w (I - dP/dsigma), dP/dsigma by central differences of the projection.
    const double h = 1e-6 * std::max(1.0, sigma.cwiseAbs().maxCoeff());
    Eigen::Matrix3d jacobian;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d step = Eigen::Vector3d::Zero();
      step[k] = h;
      jacobian.col(k) = (project(sigma + step) - project(sigma - step)) / (2.0 * h);
    }
    e.hessian = weight * (Eigen::Matrix3d::Identity() - jacobian);
    e.hessian = 0.5 * (e.hessian + e.hessian.transpose()).eval();
  }
  return e;
}

Eigen::Matrix<double, 9, 9> projected_hessian(const SignedSvd& svd, const SingularValueEnergy& energy,
                                              bool clamp_negative) {
  Eigen::Matrix<double, 9, 9> H = Eigen::Matrix<double, 9, 9>::Zero();
  auto add_mode = [&](double lambda, const Eigen::Matrix3d& mode) {
    if (clamp_negative && !(lambda > 0.0)) return;
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> q(mode.data());
    H.noalias() += lambda * q * q.transpose();
  };
  // Scaling modes: U diag(a) V^T for each eigenvector a of the sigma-space Hessian.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> scaling(energy.hessian);
  for (int k = 0; k < 3; ++k) {
    add_mode(scaling.eigenvalues()[k],
             svd.U * scaling.eigenvectors().col(k).asDiagonal() * svd.V.transpose());
  }
  const Eigen::Vector3d& s = svd.sigma;
  const Eigen::Vector3d& psi = energy.gradient;
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      Eigen::Matrix3d twist = Eigen::Matrix3d::Zero(), flip = Eigen::Matrix3d::Zero();
      twist(i, j) = -1.0 / std::sqrt(2.0);
      twist(j, i) = 1.0 / std::sqrt(2.0);
      flip(i, j) = flip(j, i) = 1.0 / std::sqrt(2.0);
      const double sum = s[i] + s[j];
      const double difference = s[i] - s[j];
      // Near-equal values: the difference quotient becomes the derivative along (1, -1).
      const double flip_lambda =
          std::abs(difference) > 1e-8 * (1.0 + std::abs(s[i]))
              ? (psi[i] - psi[j]) / difference
              : 0.5 * (energy.hessian(i, i) + energy.hessian(j, j)) - energy.hessian(i, j);
      const double twist_lambda = std::abs(sum) > 1e-12 ? (psi[i] + psi[j]) / sum : 0.0;
      add_mode(twist_lambda, svd.U * twist * svd.V.transpose());
      add_mode(flip_lambda, svd.U * flip * svd.V.transpose());
    }
  }
  return H;
}

} // namespace phantasm
