// The sliver repair by edge collapses (collapse_short_sliver_edges): the shortest edge of a
// sliver, when much shorter than its longest, collapses onto one of its vertices where that keeps
// every surface and the boundary a manifold; the vertex left without tets is removed.
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

int collapse_short_sliver_edges(TetMesh& mesh) {
  const bool labelled = mesh.subdomains.size() == mesh.tets.rows();
  const Eigen::Index vertex_count = mesh.vertices.rows();
  std::vector<std::vector<int>> star(static_cast<std::size_t>(vertex_count));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  // The regions around each vertex, -1 for the outside (a vertex of a boundary face).
  std::vector<std::set<int>> regions(static_cast<std::size_t>(vertex_count));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      regions[static_cast<std::size_t>(mesh.tets(t, k))].insert(labelled ? mesh.subdomains[t] : 0);
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      regions[static_cast<std::size_t>(mesh.boundary_faces(f, k))].insert(-1);
  std::vector<char> alive(static_cast<std::size_t>(mesh.tets.rows()), 1);
  std::vector<int> onto(static_cast<std::size_t>(vertex_count), -1); // a removed vertex's target
  const auto smallest = [&](const Eigen::Vector4i& tet) {
    const std::array<double, 6> angles = dihedral_angles_deg(tet_corners(mesh, tet));
    return *std::min_element(angles.begin(), angles.end());
  };
  const auto volume = [&](const Eigen::Vector4i& tet) {
    const std::array<Eigen::Vector3d, 4> p = tet_corners(mesh, tet);
    return signed_volume(p[0], p[1], p[2], p[3]);
  };
  // Collapses p onto q when allowed and better; true when done.
  const auto collapse = [&](int p, int q) {
    const std::set<int>& at_p = regions[static_cast<std::size_t>(p)];
    const std::set<int>& at_q = regions[static_cast<std::size_t>(q)];
    if (!std::includes(at_q.begin(), at_q.end(), at_p.begin(), at_p.end())) return false;
    std::vector<int> affected; // alive tets of p or q
    for (const int v : {p, q})
      for (const int t : star[static_cast<std::size_t>(v)])
        if (alive[static_cast<std::size_t>(t)] &&
            std::find(affected.begin(), affected.end(), t) == affected.end())
          affected.push_back(t);
    std::sort(affected.begin(), affected.end());
    double old_quality = 180.0, new_quality = 180.0;
    int old_slivers = 0, new_slivers = 0;
    std::vector<std::pair<int, Eigen::Vector4i>> kept; // tet and its new vertices
    std::vector<int> gone;
    for (const int t : affected) {
      const Eigen::Vector4i tet = mesh.tets.row(t).transpose();
      const double before = smallest(tet);
      old_quality = std::min(old_quality, before);
      old_slivers += before < k_sliver_deg;
      const bool has_p = (tet.array() == p).any(), has_q = (tet.array() == q).any();
      if (has_p && has_q) {
        gone.push_back(t);
        continue;
      }
      Eigen::Vector4i changed = tet;
      for (int k = 0; k < 4; ++k)
        if (changed[k] == p) changed[k] = q;
      if (!(volume(changed) > 0.0)) return false;
      const double after = smallest(changed);
      new_quality = std::min(new_quality, after);
      new_slivers += after < k_sliver_deg;
      kept.emplace_back(t, changed);
    }
    if (!(new_quality - old_quality > 1e-9) || new_slivers > old_slivers) return false;
    // Faces through q: at most two tets each, and the boundary around q a manifold (each edge
    // of q on none or two faces of one tet). Faces not through q are those of unchanged tets.
    std::map<FaceKey, int> count;
    for (const auto& [t, tet] : kept)
      for (int k = 0; k < 4; ++k) {
        if (tet[k] == q) continue;
        if (++count[face_key(tet, k)] > 2) return false;
      }
    std::map<int, int> boundary_faces_at; // other vertex of an edge of q -> boundary faces on it
    for (const auto& [key, n] : count) {
      if (n != 1) continue;
      for (const int v : key)
        if (v != q) ++boundary_faces_at[v];
    }
    for (const auto& [v, n] : boundary_faces_at)
      if (n != 2) return false;
    // Two tets of the same four vertices would be a fold.
    std::set<std::array<int, 4>> seen;
    for (const auto& [t, tet] : kept) {
      std::array<int, 4> sorted{tet[0], tet[1], tet[2], tet[3]};
      std::sort(sorted.begin(), sorted.end());
      if (!seen.insert(sorted).second) return false;
    }
    for (const int t : gone)
      alive[static_cast<std::size_t>(t)] = 0;
    for (const auto& [t, tet] : kept) {
      mesh.tets.row(t) = tet.transpose();
      star[static_cast<std::size_t>(q)].push_back(t);
    }
    onto[static_cast<std::size_t>(p)] = q;
    return true;
  };
  int collapses = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (!alive[static_cast<std::size_t>(t)]) continue;
    const Eigen::Vector4i tet = mesh.tets.row(t).transpose();
    if (!(smallest(tet) < k_sliver_deg)) continue;
    double shortest = std::numeric_limits<double>::infinity(), longest = 0.0;
    int a = -1, b = -1;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const double length = (mesh.vertices.row(tet[i]) - mesh.vertices.row(tet[j])).norm();
        longest = std::max(longest, length);
        if (length < shortest) {
          shortest = length;
          a = tet[i];
          b = tet[j];
        }
      }
    if (!(shortest < longest / 3.0)) continue;
    if (collapse(a, b) || collapse(b, a)) ++collapses;
  }
  if (collapses == 0) return 0;
  // Drop the collapsed tets and vertices; renumber.
  std::vector<int> index(static_cast<std::size_t>(vertex_count), -1);
  Eigen::Index next = 0;
  for (Eigen::Index v = 0; v < vertex_count; ++v)
    if (onto[static_cast<std::size_t>(v)] < 0) index[static_cast<std::size_t>(v)] = static_cast<int>(next++);
  Eigen::MatrixX3d vertices(next, 3);
  for (Eigen::Index v = 0; v < vertex_count; ++v)
    if (index[static_cast<std::size_t>(v)] >= 0)
      vertices.row(index[static_cast<std::size_t>(v)]) = mesh.vertices.row(v);
  const auto count = static_cast<Eigen::Index>(std::count(alive.begin(), alive.end(), 1));
  Eigen::MatrixX4i tets(count, 4);
  Eigen::VectorXi subdomains(labelled ? count : 0);
  Eigen::Index row = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (!alive[static_cast<std::size_t>(t)]) continue;
    for (int k = 0; k < 4; ++k)
      tets(row, k) = index[static_cast<std::size_t>(mesh.tets(t, k))];
    if (labelled) subdomains[row] = mesh.subdomains[t];
    ++row;
  }
  // Boundary faces: a removed vertex's become its target's; those on the collapsed edge vanish.
  const auto final_vertex = [&](int v) {
    while (onto[static_cast<std::size_t>(v)] >= 0)
      v = onto[static_cast<std::size_t>(v)];
    return index[static_cast<std::size_t>(v)];
  };
  std::vector<Eigen::Vector3i> boundary;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    const Eigen::Vector3i face(final_vertex(mesh.boundary_faces(f, 0)),
                               final_vertex(mesh.boundary_faces(f, 1)),
                               final_vertex(mesh.boundary_faces(f, 2)));
    if (face[0] != face[1] && face[1] != face[2] && face[0] != face[2]) boundary.push_back(face);
  }
  mesh.vertices = std::move(vertices);
  mesh.tets = std::move(tets);
  mesh.subdomains = std::move(subdomains);
  mesh.boundary_faces.resize(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t f = 0; f < boundary.size(); ++f)
    mesh.boundary_faces.row(static_cast<Eigen::Index>(f)) = boundary[f].transpose();
  return collapses;
}

} // namespace phantasm
