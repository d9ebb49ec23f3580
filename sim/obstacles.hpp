// Rigid obstacles the model's free vertices may not enter (half-spaces and spheres), with their
// frictionless penalty and projection.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace phantasm {

/// A rigid obstacle the model's free vertices may not enter (docs/method.md section 3.8, collision): a
/// half-space (a compression plate, a table) or a solid sphere (a probe tip, a finger). A vertex inside
/// costs contact_stiffness / 2 times its squared distance to the allowed region; its projection
/// is the closest allowed point, on the obstacle's boundary. The penalty is C1 and acts along
/// the boundary's normal only (frictionless contact).
struct Obstacle {
  enum class Shape { half_space, sphere };
  Shape shape = Shape::half_space;
  /// half-space: a point of its boundary plane; sphere: the centre (metres)
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();
  /// half-space: unit normal pointing out of the obstacle, into the allowed region
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double radius_m = 0.0; ///< sphere only

  /// Distance of x from the boundary, negative inside the obstacle.
  double signed_distance(const Eigen::Vector3d& x) const;
  /// Unit normal of the boundary at the projection of x, pointing into the allowed region.
  Eigen::Vector3d outward_normal(const Eigen::Vector3d& x) const;
  /// The closest allowed point to x: x itself outside, the boundary point below x inside. The
  /// centre of a sphere (no closest point) goes out along +z.
  Eigen::Vector3d project(const Eigen::Vector3d& x) const;
};

/// Contact energy of one vertex against every obstacle: sum over obstacles it is inside of
/// k/2 |x - P(x)|^2.
double contact_energy(const std::vector<Obstacle>& obstacles, double stiffness_N_m, const Eigen::Vector3d& x);

/// Its gradient, sum of k (x - P(x)).
Eigen::Vector3d contact_gradient(const std::vector<Obstacle>& obstacles, double stiffness_N_m,
                                 const Eigen::Vector3d& x);

/// A positive semi-definite Hessian: k n n^T for every obstacle x is inside (exact for the
/// half-space; for a sphere it leaves out the negative curvature along the surface).
Eigen::Matrix3d contact_hessian(const std::vector<Obstacle>& obstacles, double stiffness_N_m,
                                const Eigen::Vector3d& x);

} // namespace phantasm
