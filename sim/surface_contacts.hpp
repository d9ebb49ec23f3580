// Contacts between organs' surfaces: closed surfaces whose interior paired surfaces' vertices
// may not enter, and where a point is against them.
#pragma once

#include "geometry/mesh_signed_distance.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace phantasm {

/// A closed, outward triangle surface of the model (a solid body's boundary, or a closed shell)
/// whose interior the vertices of the surfaces it is paired with may not enter (docs/method.md
/// section 3.8, collision with another organ's surface).
struct ContactSurface {
  std::vector<int> vertices;                 ///< model vertices on the surface
  std::vector<std::array<int, 3>> triangles; ///< model vertex indices, outward
};

/// For each of `vertex_count` model vertices, the surfaces it may not enter: those paired (in
/// `pairs`, both ways) with a surface it belongs to.
std::vector<std::vector<int>> opposing_surfaces(const std::vector<ContactSurface>& surfaces,
                                                const std::vector<std::array<int, 2>>& pairs,
                                                Eigen::Index vertex_count);

/// Where a point is against a surface: inside or not, and the closest point of the surface with
/// the normal of its contact plane (the face normal, or at an edge or corner the angle-weighted
/// pseudonormal of Baerentzen and Aanaes 2005, whose sign against x - closest is the inside test).
struct SurfaceQuery {
  bool inside = false;
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< outward, unit
  double distance = 0.0;
  std::array<int, 3> triangle{};                         ///< model vertices of the closest point's triangle
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero(); ///< the closest point over them
};

/// The surfaces' current geometry for point queries: triangle normals, edge and vertex
/// pseudonormals and bounding boxes, refreshed from positions by update() (each local step).
class ContactGeometry {
public:
  explicit ContactGeometry(const std::vector<ContactSurface>& surfaces);

  /// Recomputes normals and bounds at positions p (one row per model vertex).
  void update(const Eigen::MatrixX3d& p);

  /// x against surface s (positions of the last update). Points outside its bounding box are
  /// outside without a closest-point search.
  SurfaceQuery query(int s, const Eigen::Vector3d& x) const;

private:
  std::vector<SignedDistanceMesh> m_meshes; ///< per surface
};

} // namespace phantasm
