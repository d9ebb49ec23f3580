// The sliver repairs that leave every vertex where it is: peeling flat tets off the boundary
// (peel_boundary_slivers) and giving a lone tet wedged between other regions the region it
// shares most faces with (relabel_stranded_slivers).
#include "anatomy/sliver_repairs.hpp"

#include "anatomy/sliver_faces.hpp"
#include "geometry/tet_quality.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace phantasm {

namespace {

/// The tets of every face (one for a boundary face, two inside).
std::map<FaceKey, std::vector<int>> tets_of_faces(const TetMesh& mesh) {
  std::map<FaceKey, std::vector<int>> faces;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      faces[face_key(mesh, t, k)].push_back(static_cast<int>(t));
  return faces;
}

bool is_sliver(const TetMesh& mesh, Eigen::Index t, double bound_deg) {
  const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
  return *std::min_element(angles.begin(), angles.end()) < bound_deg;
}

double face_area(const TetMesh& mesh, const FaceKey& key) {
  const Eigen::Vector3d a = mesh.vertices.row(key[0]), b = mesh.vertices.row(key[1]),
                        c = mesh.vertices.row(key[2]);
  return 0.5 * (b - a).cross(c - a).norm();
}

} // namespace

int peel_boundary_slivers(TetMesh& mesh, double bound_deg) {
  const Eigen::Index count = mesh.tets.rows();
  std::map<FaceKey, std::vector<int>> faces = tets_of_faces(mesh);
  std::vector<std::vector<int>> star(static_cast<std::size_t>(mesh.vertices.rows()));
  for (Eigen::Index t = 0; t < count; ++t)
    for (int k = 0; k < 4; ++k)
      star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  std::vector<char> removed(static_cast<std::size_t>(count), 0);
  std::vector<FaceKey> exposed; // faces that became boundary, in order
  // True when a face of a remaining tet holding vertices c and d is a boundary face.
  const auto on_boundary = [&](int c, int d) {
    for (const int u : star[static_cast<std::size_t>(c)]) {
      if (removed[static_cast<std::size_t>(u)]) continue;
      for (int k = 0; k < 4; ++k) {
        const int opposite = mesh.tets(u, k);
        if (opposite == c || opposite == d) continue;
        const FaceKey key = face_key(mesh, u, k);
        if (std::find(key.begin(), key.end(), d) == key.end()) continue;
        if (faces[key].size() == 1) return true;
      }
    }
    return false;
  };
  int peeled = 0;
  for (Eigen::Index t = 0; t < count; ++t) {
    if (!is_sliver(mesh, t, bound_deg)) continue;
    std::vector<int> outer, inner; // local vertex indices opposite boundary / inner faces
    for (int k = 0; k < 4; ++k)
      (faces[face_key(mesh, t, k)].size() == 1 ? outer : inner).push_back(k);
    if (outer.size() != 2) continue;
    // The inner faces (opposite inner[0] and inner[1]) share the edge of the vertices opposite
    // the boundary faces: it must not be on the boundary already.
    if (on_boundary(mesh.tets(t, outer[0]), mesh.tets(t, outer[1]))) continue;
    removed[static_cast<std::size_t>(t)] = 1;
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = face_key(mesh, t, k);
      std::vector<int>& around = faces[key];
      around.erase(std::find(around.begin(), around.end(), static_cast<int>(t)));
      if (around.empty())
        faces.erase(key);
      else
        exposed.push_back(key);
    }
    ++peeled;
  }
  if (peeled == 0) return 0;
  Eigen::MatrixX4i tets(count - peeled, 4);
  Eigen::VectorXi subdomains(mesh.subdomains.size() == count ? count - peeled : 0);
  std::vector<int> new_index(static_cast<std::size_t>(count), -1);
  Eigen::Index kept = 0;
  for (Eigen::Index t = 0; t < count; ++t) {
    if (removed[static_cast<std::size_t>(t)]) continue;
    new_index[static_cast<std::size_t>(t)] = static_cast<int>(kept);
    tets.row(kept) = mesh.tets.row(t);
    if (subdomains.size() > 0) subdomains[kept] = mesh.subdomains[t];
    ++kept;
  }
  std::vector<Eigen::Vector3i> boundary;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    FaceKey key{mesh.boundary_faces(f, 0), mesh.boundary_faces(f, 1), mesh.boundary_faces(f, 2)};
    std::sort(key.begin(), key.end());
    const auto found = faces.find(key);
    if (found != faces.end() && found->second.size() == 1) boundary.push_back(mesh.boundary_faces.row(f));
  }
  for (const FaceKey& key : exposed) {
    const auto found = faces.find(key);
    if (found == faces.end() || found->second.size() != 1) continue; // peeled later itself
    const int u = found->second.front();
    for (int k = 0; k < 4; ++k)
      if (face_key(mesh, u, k) == key)
        boundary.emplace_back(mesh.tets(u, k_outward_face[k][0]), mesh.tets(u, k_outward_face[k][1]),
                              mesh.tets(u, k_outward_face[k][2]));
  }
  mesh.boundary_faces.resize(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t f = 0; f < boundary.size(); ++f)
    mesh.boundary_faces.row(static_cast<Eigen::Index>(f)) = boundary[f].transpose();
  mesh.tets = std::move(tets);
  mesh.subdomains = std::move(subdomains);
  return peeled;
}

int relabel_stranded_slivers(TetMesh& mesh, double bound_deg) {
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  const std::map<FaceKey, std::vector<int>> faces = tets_of_faces(mesh);
  int relabelled = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (!is_sliver(mesh, t, bound_deg)) continue;
    const int own = mesh.subdomains[t];
    std::map<int, std::pair<int, double>> shared; // region -> faces, their area
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = face_key(mesh, t, k);
      const std::vector<int>& around = faces.at(key);
      if (around.size() != 2) continue;
      const int other = around[0] == static_cast<int>(t) ? around[1] : around[0];
      auto& [number, area] = shared[mesh.subdomains[other]];
      ++number;
      area += face_area(mesh, key);
    }
    shared[own]; // present, with no faces when none is shared with its own region
    int best = own;
    for (const auto& [region, tally] : shared) {
      if (region == own) continue;
      const auto& best_tally = shared[best];
      if (best == own || tally.first > best_tally.first ||
          (tally.first == best_tally.first && tally.second > best_tally.second))
        best = region;
    }
    if (best == own || shared[best].first <= shared[own].first) continue;
    mesh.subdomains[t] = best;
    ++relabelled;
  }
  return relabelled;
}

} // namespace phantasm
