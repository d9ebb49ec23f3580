// The closest point of a triangle to a point (Ericson's Voronoi region test), with its barycentric
// coordinates and the feature (interior, edge or corner) it lies on.
#pragma once

#include <Eigen/Core>

namespace phantasm {

/// The feature of a triangle a closest point lies on.
enum class TriangleFeature { face, edge, vertex };

/// A point of triangle (a, b, c) closest to a query point.
struct TriangleClosestPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       ///< in the units of the corners (mm)
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero(); ///< weights of (a, b, c): each in [0, 1], sum 1
  TriangleFeature feature = TriangleFeature::face;
  /// The edge k (between corners k and k + 1 mod 3: 0 = ab, 1 = bc, 2 = ca) or the corner k
  /// (0 = a, 1 = b, 2 = c); 0 for the interior.
  int index = 0;
};

/// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection, 5.1.5):
/// the Voronoi regions of the corners, then of the edges, then the interior. A triangle without
/// area (coincident corners, or sin^2 of its angle at a below 1e-20) is taken as its three edges.
/// @param p query point, mm (any unit: the result is in the same)
/// @param a, b, c corners, mm
TriangleClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c);

} // namespace phantasm
