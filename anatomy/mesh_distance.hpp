#pragma once

#include "anatomy/triangle_mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace phantasm {

/// Closest points on a triangle mesh, with a uniform grid of buckets for speed, and the sign of
/// the distance from angle-weighted pseudonormals (Baerentzen and Aanaes 2005), so points inside
/// a closed outward mesh get negative distances.
class MeshDistance {
public:
  explicit MeshDistance(const TriangleMesh& mesh);

  /// Unsigned distance from x to the mesh, mm.
  double distance(const Eigen::Vector3d& x) const;
  /// Signed distance: negative inside a closed, outward-oriented mesh, mm.
  double signed_distance(const Eigen::Vector3d& x) const;

private:
  struct Closest {
    double distance_squared;
    Eigen::Vector3d point;
    Eigen::Index triangle;
    int feature; ///< 0: face interior, 1..3: vertex k-1, 4..6: edge (k-4, k-3)
  };
  Closest closest(const Eigen::Vector3d& x) const;
  Eigen::Vector3i cell_of(const Eigen::Vector3d& x) const;
  const std::vector<Eigen::Index>& bucket(const Eigen::Vector3i& cell) const;

  TriangleMesh m_mesh;
  Eigen::Vector3d m_min, m_cell_size;
  Eigen::Vector3i m_cells;
  std::vector<std::vector<Eigen::Index>> m_buckets;
  Eigen::MatrixX3d m_face_normals, m_vertex_normals;
  std::vector<std::array<Eigen::Vector3d, 3>> m_edge_normals; ///< per face, per edge k (k, k+1)
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
