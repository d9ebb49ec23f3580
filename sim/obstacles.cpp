#include "sim/obstacles.hpp"

namespace phantasm {

double Obstacle::signed_distance(const Eigen::Vector3d& x) const {
  if (shape == Shape::half_space) return normal.dot(x - point_m);
  return (x - point_m).norm() - radius_m;
}

Eigen::Vector3d Obstacle::outward_normal(const Eigen::Vector3d& x) const {
  if (shape == Shape::half_space) return normal;
  const Eigen::Vector3d r = x - point_m;
  const double length = r.norm();
  return length > 0.0 ? Eigen::Vector3d(r / length) : Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d Obstacle::project(const Eigen::Vector3d& x) const {
  const double d = signed_distance(x);
  if (d >= 0.0) return x;
  if (shape == Shape::half_space) return x - d * normal;
  return point_m + radius_m * outward_normal(x);
}

double contact_energy(const std::vector<Obstacle>& obstacles, double stiffness_N_m,
                      const Eigen::Vector3d& x) {
  double energy = 0.0;
  for (const Obstacle& o : obstacles) {
    const double d = o.signed_distance(x);
    if (d < 0.0) energy += 0.5 * stiffness_N_m * (x - o.project(x)).squaredNorm();
  }
  return energy;
}

Eigen::Vector3d contact_gradient(const std::vector<Obstacle>& obstacles, double stiffness_N_m,
                                 const Eigen::Vector3d& x) {
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (const Obstacle& o : obstacles)
    if (o.signed_distance(x) < 0.0) g += stiffness_N_m * (x - o.project(x));
  return g;
}

Eigen::Matrix3d contact_hessian(const std::vector<Obstacle>& obstacles, double stiffness_N_m,
                                const Eigen::Vector3d& x) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (const Obstacle& o : obstacles) {
    if (o.signed_distance(x) >= 0.0) continue;
    const Eigen::Vector3d n = o.outward_normal(x);
    H.noalias() += stiffness_N_m * n * n.transpose();
  }
  return H;
}

} // namespace phantasm
