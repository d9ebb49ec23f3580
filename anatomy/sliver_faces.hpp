// What the sliver repairs (anatomy/sliver_repairs.hpp) share: the bound under which a tet counts
// as a sliver, and the faces of a tet as sorted keys (to find the tets on each side of a face).
#pragma once

#include "geometry/tet_mesh.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>

namespace phantasm {

/// A tet with a dihedral angle under this is counted as a sliver (the log's "tets under 10 deg"):
/// the repairs may raise the smallest angle of the tets they change, but not leave more slivers.
inline constexpr double k_sliver_deg = 10.0;

/// The faces of a positively oriented tet, each opposite one vertex, oriented outward.
inline constexpr int k_outward_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

using FaceKey = std::array<int, 3>;

/// The face of `tet` opposite its vertex `opposite`, its vertices sorted.
inline FaceKey face_key(const Eigen::Vector4i& tet, int opposite) {
  FaceKey key{tet[k_outward_face[opposite][0]], tet[k_outward_face[opposite][1]],
              tet[k_outward_face[opposite][2]]};
  std::sort(key.begin(), key.end());
  return key;
}

inline FaceKey face_key(const TetMesh& mesh, Eigen::Index t, int opposite) {
  return face_key(Eigen::Vector4i(mesh.tets.row(t).transpose()), opposite);
}

} // namespace phantasm
