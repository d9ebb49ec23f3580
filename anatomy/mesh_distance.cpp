#include "anatomy/mesh_distance.hpp"

#include "core/cancellation.hpp"

#include <algorithm>
#include <cmath>

namespace phantasm {

MeshDistance::MeshDistance(const TriangleMesh& mesh) : m_mesh(mesh.faces) {
  m_mesh.update(mesh.vertices);
  m_mesh.build_search_tree();
}

SurfaceDistance symmetric_distance(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& samples_on_b,
                                   const std::vector<double>& mesh_vertex_distances_to_b) {
  SurfaceDistance result;
  const MeshDistance to_mesh(mesh);
  double total = 0.0;
  for (const auto& p : samples_on_b) {
    throw_if_cancelled();
    const double d = to_mesh.distance(p);
    result.hausdorff_mm = std::max(result.hausdorff_mm, d);
    total += d;
  }
  for (double d : mesh_vertex_distances_to_b) {
    result.hausdorff_mm = std::max(result.hausdorff_mm, std::abs(d));
    total += std::abs(d);
  }
  result.mean_mm = total / static_cast<double>(samples_on_b.size() + mesh_vertex_distances_to_b.size());
  return result;
}

} // namespace phantasm
