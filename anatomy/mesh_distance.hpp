// Signed and unsigned distances to a triangle mesh, and the symmetric Hausdorff and mean distance
// between two surfaces, with which patch fits are measured against their targets.
#pragma once

#include "geometry/mesh_signed_distance.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace phantasm {

/// Distances to a triangle mesh, with a uniform grid of buckets for speed, and the sign of the
/// distance from angle-weighted pseudonormals (Baerentzen and Aanaes 2005), so points inside a
/// closed outward mesh get negative distances (geometry/mesh_signed_distance.hpp).
class MeshDistance {
public:
  explicit MeshDistance(const TriangleMesh& mesh);

  /// Unsigned distance from x to the mesh, mm.
  double distance(const Eigen::Vector3d& x) const { return m_mesh.distance(x); }
  /// Signed distance: negative inside a closed, outward-oriented mesh, mm.
  double signed_distance(const Eigen::Vector3d& x) const { return m_mesh.signed_distance(x); }
  /// The closest point, its search started from triangle `hint` (-1: none); the same answer,
  /// ties included (SignedDistanceMesh::closest).
  MeshClosestPoint closest(const Eigen::Vector3d& x, int hint) const { return m_mesh.closest(x, hint); }

private:
  SignedDistanceMesh m_mesh;
};

/// Distances between two surfaces, in mm.
struct SurfaceDistance {
  double hausdorff_mm = 0.0; ///< largest distance either way
  double mean_mm = 0.0;      ///< mean over both samplings
};

/// Symmetric distances between a mesh and the points sampled on another surface: `samples` lie
/// on surface B, `mesh` approximates surface A, and `distance_to_b` gives distances to B.
SurfaceDistance symmetric_distance(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& samples_on_b,
                                   const std::vector<double>& mesh_vertex_distances_to_b);

} // namespace phantasm
