// The boundary of a tet mesh, oriented outward; see tet_boundary.hpp.
#include "geometry/tet_boundary.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <map>
#include <vector>

namespace phantasm {

Eigen::MatrixX3i tet_boundary_faces(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& tets) {
  struct Face {
    std::array<int, 3> corners;
    int opposite;
    int count;
  };
  // A face is shared by at most two tets: keyed by its sorted vertices, it is on the boundary
  // when one tet uses it.
  std::map<std::array<int, 3>, Face> faces;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f = {tets(t, (k + 1) % 4), tets(t, (k + 2) % 4), tets(t, (k + 3) % 4)};
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, Face{f, tets(t, k), 0});
      ++it->second.count;
    }
  }
  std::vector<Eigen::Vector3i> boundary;
  for (const auto& [key, face] : faces) {
    if (face.count != 1) continue;
    Eigen::Vector3i f(face.corners[0], face.corners[1], face.corners[2]);
    const Eigen::Vector3d a = vertices.row(f[0]).transpose();
    const Eigen::Vector3d normal =
        (vertices.row(f[1]).transpose() - a).cross(vertices.row(f[2]).transpose() - a);
    if (normal.dot(vertices.row(face.opposite).transpose() - a) > 0.0) std::swap(f[1], f[2]);
    boundary.push_back(f);
  }
  Eigen::MatrixX3i result(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t i = 0; i < boundary.size(); ++i)
    result.row(static_cast<Eigen::Index>(i)) = boundary[i].transpose();
  return result;
}

} // namespace phantasm
