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

namespace {

/// The tets a collapse changes (each with its new vertices) and those it removes.
struct CollapseChange {
  std::vector<std::pair<int, Eigen::Vector4i>> kept; // tet and its new vertices
  std::vector<int> gone;
};

/// The edge collapses of a mesh: the tets around each vertex, the regions each vertex touches,
/// which tets remain and where each removed vertex went.
class CollapseRepair {
public:
  explicit CollapseRepair(TetMesh& mesh)
      : m_mesh(mesh), m_labelled(mesh.subdomains.size() == mesh.tets.rows()),
        m_vertex_count(mesh.vertices.rows()), m_star(static_cast<std::size_t>(m_vertex_count)),
        m_regions(static_cast<std::size_t>(m_vertex_count)),
        m_alive(static_cast<std::size_t>(mesh.tets.rows()), 1),
        m_onto(static_cast<std::size_t>(m_vertex_count), -1) {
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
      for (int k = 0; k < 4; ++k)
        m_star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
    // The regions around each vertex, -1 for the outside (a vertex of a boundary face).
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
      for (int k = 0; k < 4; ++k)
        m_regions[static_cast<std::size_t>(mesh.tets(t, k))].insert(m_labelled ? mesh.subdomains[t] : 0);
    for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        m_regions[static_cast<std::size_t>(mesh.boundary_faces(f, k))].insert(-1);
  }

  /// Tet t's shortest edge collapsed (either way) when t is a sliver whose shortest edge is
  /// under a third of its longest; true when done.
  bool collapse_tet(Eigen::Index t) {
    if (!m_alive[static_cast<std::size_t>(t)]) return false;
    const Eigen::Vector4i tet = m_mesh.tets.row(t).transpose();
    if (!(smallest(tet) < k_sliver_deg)) return false;
    double shortest = std::numeric_limits<double>::infinity(), longest = 0.0;
    int a = -1, b = -1;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const double length = (m_mesh.vertices.row(tet[i]) - m_mesh.vertices.row(tet[j])).norm();
        longest = std::max(longest, length);
        if (length < shortest) {
          shortest = length;
          a = tet[i];
          b = tet[j];
        }
      }
    if (!(shortest < longest / 3.0)) return false;
    return collapse(a, b) || collapse(b, a);
  }

  /// Drops the collapsed tets and vertices and renumbers; a removed vertex's boundary faces
  /// become its target's, those on the collapsed edge vanish.
  void renumber() {
    TetMesh& mesh = m_mesh;
    std::vector<int> index(static_cast<std::size_t>(m_vertex_count), -1);
    Eigen::Index next = 0;
    for (Eigen::Index v = 0; v < m_vertex_count; ++v)
      if (m_onto[static_cast<std::size_t>(v)] < 0)
        index[static_cast<std::size_t>(v)] = static_cast<int>(next++);
    Eigen::MatrixX3d vertices(next, 3);
    for (Eigen::Index v = 0; v < m_vertex_count; ++v)
      if (index[static_cast<std::size_t>(v)] >= 0)
        vertices.row(index[static_cast<std::size_t>(v)]) = mesh.vertices.row(v);
    const auto count = static_cast<Eigen::Index>(std::count(m_alive.begin(), m_alive.end(), 1));
    Eigen::MatrixX4i tets(count, 4);
    Eigen::VectorXi subdomains(m_labelled ? count : 0);
    Eigen::Index row = 0;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      if (!m_alive[static_cast<std::size_t>(t)]) continue;
      for (int k = 0; k < 4; ++k)
        tets(row, k) = index[static_cast<std::size_t>(mesh.tets(t, k))];
      if (m_labelled) subdomains[row] = mesh.subdomains[t];
      ++row;
    }
    const auto final_vertex = [&](int v) {
      while (m_onto[static_cast<std::size_t>(v)] >= 0)
        v = m_onto[static_cast<std::size_t>(v)];
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
  }

private:
  double smallest(const Eigen::Vector4i& tet) const {
    const std::array<double, 6> angles = dihedral_angles_deg(tet_corners(m_mesh, tet));
    return *std::min_element(angles.begin(), angles.end());
  }
  double volume(const Eigen::Vector4i& tet) const {
    const std::array<Eigen::Vector3d, 4> p = tet_corners(m_mesh, tet);
    return signed_volume(p[0], p[1], p[2], p[3]);
  }

  /// The alive tets of p or q with p moved onto q: false when one inverts, or when the smallest
  /// angle does not rise or slivers are added.
  bool changed_tets(int p, int q, CollapseChange& change) const {
    std::vector<int> affected; // alive tets of p or q
    for (const int v : {p, q})
      for (const int t : m_star[static_cast<std::size_t>(v)])
        if (m_alive[static_cast<std::size_t>(t)] &&
            std::find(affected.begin(), affected.end(), t) == affected.end())
          affected.push_back(t);
    std::sort(affected.begin(), affected.end());
    double old_quality = 180.0, new_quality = 180.0;
    int old_slivers = 0, new_slivers = 0;
    for (const int t : affected) {
      const Eigen::Vector4i tet = m_mesh.tets.row(t).transpose();
      const double before = smallest(tet);
      old_quality = std::min(old_quality, before);
      old_slivers += before < k_sliver_deg;
      const bool has_p = (tet.array() == p).any(), has_q = (tet.array() == q).any();
      if (has_p && has_q) {
        change.gone.push_back(t);
        continue;
      }
      Eigen::Vector4i changed = tet;
      for (int k = 0; k < 4; ++k)
        if (changed[k] == p) changed[k] = q;
      if (!(volume(changed) > 0.0)) return false;
      const double after = smallest(changed);
      new_quality = std::min(new_quality, after);
      new_slivers += after < k_sliver_deg;
      change.kept.emplace_back(t, changed);
    }
    return new_quality - old_quality > 1e-9 && new_slivers <= old_slivers;
  }

  /// Faces through q: at most two tets each, and the boundary around q a manifold (each edge of
  /// q on none or two faces of one tet); faces not through q are those of unchanged tets. And no
  /// two tets of the same four vertices (a fold).
  static bool stays_manifold(int q, const CollapseChange& change) {
    std::map<FaceKey, int> count;
    for (const auto& [t, tet] : change.kept)
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
    std::set<std::array<int, 4>> seen;
    for (const auto& [t, tet] : change.kept) {
      std::array<int, 4> sorted{tet[0], tet[1], tet[2], tet[3]};
      std::sort(sorted.begin(), sorted.end());
      if (!seen.insert(sorted).second) return false;
    }
    return true;
  }

  /// Collapses p onto q when allowed and better; true when done.
  bool collapse(int p, int q) {
    const std::set<int>& at_p = m_regions[static_cast<std::size_t>(p)];
    const std::set<int>& at_q = m_regions[static_cast<std::size_t>(q)];
    if (!std::includes(at_q.begin(), at_q.end(), at_p.begin(), at_p.end())) return false;
    CollapseChange change;
    if (!changed_tets(p, q, change) || !stays_manifold(q, change)) return false;
    for (const int t : change.gone)
      m_alive[static_cast<std::size_t>(t)] = 0;
    for (const auto& [t, tet] : change.kept) {
      m_mesh.tets.row(t) = tet.transpose();
      m_star[static_cast<std::size_t>(q)].push_back(t);
    }
    m_onto[static_cast<std::size_t>(p)] = q;
    return true;
  }

  TetMesh& m_mesh;
  bool m_labelled;
  Eigen::Index m_vertex_count;
  std::vector<std::vector<int>> m_star;
  std::vector<std::set<int>> m_regions;
  std::vector<char> m_alive;
  std::vector<int> m_onto; // a removed vertex's target
};

} // namespace

int collapse_short_sliver_edges(TetMesh& mesh) {
  CollapseRepair repair(mesh);
  int collapses = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    if (repair.collapse_tet(t)) ++collapses;
  if (collapses == 0) return 0;
  repair.renumber();
  return collapses;
}

} // namespace phantasm
