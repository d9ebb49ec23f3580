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
  // The distances in parallel, summed in sample order: the same result on any thread count.
  std::vector<double> distances(samples_on_b.size());
  const auto count = static_cast<std::ptrdiff_t>(samples_on_b.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < count; ++i) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    distances[static_cast<std::size_t>(i)] = to_mesh.distance(samples_on_b[static_cast<std::size_t>(i)]);
  }
  throw_if_cancelled();
  double total = 0.0;
  for (const double d : distances) {
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
