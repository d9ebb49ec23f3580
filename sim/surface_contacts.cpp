#include "sim/surface_contacts.hpp"

#include <algorithm>
#include <cmath>

namespace phantasm {

std::vector<std::vector<int>> opposing_surfaces(const std::vector<ContactSurface>& surfaces,
                                                const std::vector<std::array<int, 2>>& pairs,
                                                Eigen::Index vertex_count) {
  std::vector<std::vector<int>> opposing(static_cast<std::size_t>(vertex_count));
  for (const auto& [a, b] : pairs) {
    for (const auto& [own, other] : {std::pair{a, b}, std::pair{b, a}}) {
      for (int v : surfaces[static_cast<std::size_t>(own)].vertices) {
        auto& list = opposing[static_cast<std::size_t>(v)];
        if (std::find(list.begin(), list.end(), other) == list.end()) list.push_back(other);
      }
    }
  }
  return opposing;
}

ContactGeometry::ContactGeometry(const std::vector<ContactSurface>& surfaces) {
  m_meshes.reserve(surfaces.size());
  for (const ContactSurface& surface : surfaces)
    m_meshes.emplace_back(surface.triangles);
}

void ContactGeometry::update(const Eigen::MatrixX3d& p) {
  for (SignedDistanceMesh& mesh : m_meshes)
    mesh.update(p);
}

SurfaceQuery ContactGeometry::query(int s, const Eigen::Vector3d& x) const {
  SurfaceQuery q;
  const SignedDistanceMesh& mesh = m_meshes[static_cast<std::size_t>(s)];
  if (!mesh.in_bounds(x)) return q;
  const MeshClosestPoint c = mesh.closest(x);
  if (c.triangle < 0) return q;
  const Eigen::Vector3d pseudonormal = mesh.pseudonormal(c);
  const Eigen::Vector3d offset = x - c.on_triangle.point;
  q.closest = c.on_triangle.point;
  q.triangle = mesh.triangles()[static_cast<std::size_t>(c.triangle)];
  q.barycentric = c.on_triangle.barycentric;
  q.distance = std::sqrt(c.distance_squared);
  q.inside = offset.dot(pseudonormal) < 0.0;
  // The contact plane's normal: along the offset where there is one, else the pseudonormal.
  if (q.distance > 1e-12 * (mesh.max() - mesh.min()).norm())
    q.normal = (q.inside ? -offset : offset) / q.distance;
  else
    q.normal = pseudonormal.normalized();
  return q;
}

} // namespace phantasm
