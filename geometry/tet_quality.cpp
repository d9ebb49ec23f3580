// Element quality of tet meshes: volumes, dihedral angles, edge lengths (geometry/tet_quality.hpp).

#include "geometry/tet_quality.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace phantasm {

double tet_volume(const TetMesh& mesh, Eigen::Index t) {
  const Eigen::Vector3d a = mesh.vertices.row(mesh.tets(t, 0)).transpose();
  const Eigen::Vector3d b = mesh.vertices.row(mesh.tets(t, 1)).transpose();
  const Eigen::Vector3d c = mesh.vertices.row(mesh.tets(t, 2)).transpose();
  const Eigen::Vector3d d = mesh.vertices.row(mesh.tets(t, 3)).transpose();
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

std::array<double, 6> dihedral_angles_deg(const std::array<Eigen::Vector3d, 4>& p) {
  // Outward face normals; face k is opposite vertex k.
  Eigen::Vector3d n[4];
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d a = p[static_cast<std::size_t>((k + 1) % 4)],
                          b = p[static_cast<std::size_t>((k + 2) % 4)],
                          c = p[static_cast<std::size_t>((k + 3) % 4)];
    n[k] = (b - a).cross(c - a).normalized();
    if (n[k].dot(p[static_cast<std::size_t>(k)] - a) > 0.0) n[k] = -n[k];
  }
  std::array<double, 6> angles;
  int i = 0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      // The dihedral angle at the edge shared by faces a and b is pi minus the angle of their normals.
      angles[static_cast<std::size_t>(i++)] =
          180.0 - std::acos(std::clamp(n[a].dot(n[b]), -1.0, 1.0)) * 180.0 / M_PI;
    }
  }
  return angles;
}

std::array<Eigen::Vector3d, 4> tet_corners(const TetMesh& mesh, const Eigen::Vector4i& tet) {
  std::array<Eigen::Vector3d, 4> p;
  for (int k = 0; k < 4; ++k)
    p[static_cast<std::size_t>(k)] = mesh.vertices.row(tet[k]).transpose();
  return p;
}

std::array<double, 6> tet_dihedral_angles_deg(const TetMesh& mesh, Eigen::Index t) {
  return dihedral_angles_deg(tet_corners(mesh, mesh.tets.row(t).transpose()));
}

double min_dihedral_angle_deg(const TetMesh& mesh) {
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (double angle : tet_dihedral_angles_deg(mesh, t))
      smallest = std::min(smallest, angle);
  }
  return smallest;
}

Eigen::Index tets_with_dihedral_below(const TetMesh& mesh, double bound_deg) {
  Eigen::Index count = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
    count += *std::min_element(angles.begin(), angles.end()) < bound_deg;
  }
  return count;
}

double mean_edge_length(const TetMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        edges.emplace_back(std::minmax(mesh.tets(t, a), mesh.tets(t, b)));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  double sum = 0.0;
  for (const auto& [a, b] : edges)
    sum += (mesh.vertices.row(a) - mesh.vertices.row(b)).norm();
  return edges.empty() ? 0.0 : sum / static_cast<double>(edges.size());
}

double signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

} // namespace phantasm
