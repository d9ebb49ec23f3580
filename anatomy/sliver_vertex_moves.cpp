// The sliver repair that moves vertices (improve_slivers): each vertex of a sliver tries steps in
// fixed directions, within its interface's tangent plane when it lies on one, and keeps the one
// that most raises the smallest dihedral angle around it.
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

/// True when tet t's centroid lies in its own subdomain.
bool centroid_in_subdomain(const TetMesh& mesh, int t,
                           const std::function<int(const Eigen::Vector3d&)>& label) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    centroid += 0.25 * mesh.vertices.row(mesh.tets(t, k)).transpose();
  return label(centroid) == mesh.subdomains[t];
}

/// The smallest dihedral angle of the tets in `star` with vertex v at x, degrees; -1 when one of
/// them would not be positively oriented, or one whose centroid lies in its subdomain
/// (`in_subdomain`, per tet of the star) would leave it. `below`: how many of them have an angle
/// under bound_deg.
double star_quality(TetMesh& mesh, const std::vector<int>& star, const std::vector<bool>& in_subdomain, int v,
                    const Eigen::Vector3d& x, const std::function<int(const Eigen::Vector3d&)>& label,
                    double bound_deg, int& below) {
  const Eigen::Vector3d saved = mesh.vertices.row(v).transpose();
  mesh.vertices.row(v) = x.transpose();
  double smallest = std::numeric_limits<double>::infinity();
  below = 0;
  for (std::size_t i = 0; i < star.size(); ++i) {
    const int t = star[i];
    Eigen::Vector3d p[4];
    for (int k = 0; k < 4; ++k)
      p[k] = mesh.vertices.row(mesh.tets(t, k)).transpose();
    if (!(signed_volume(p[0], p[1], p[2], p[3]) > 0.0) ||
        (in_subdomain[i] && !centroid_in_subdomain(mesh, t, label))) {
      smallest = -1.0;
      break;
    }
    const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
    const double tet_smallest = *std::min_element(angles.begin(), angles.end());
    smallest = std::min(smallest, tet_smallest);
    below += tet_smallest < bound_deg;
  }
  mesh.vertices.row(v) = saved.transpose();
  return smallest;
}

/// Around each vertex: its tets, the regions it touches (-1: outside, for vertices of the
/// boundary) and, on an interface of two regions, the interface's normal (area-weighted, from the
/// smaller label's side to the larger's).
struct VertexSurroundings {
  std::vector<std::vector<int>> star;
  std::vector<std::set<int>> regions;
  std::vector<Eigen::Vector3d> normal;
};

VertexSurroundings vertex_surroundings(const TetMesh& mesh) {
  const Eigen::Index nv = mesh.vertices.rows();
  VertexSurroundings s;
  s.star.resize(static_cast<std::size_t>(nv));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      s.star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  std::map<std::array<int, 3>, std::vector<int>> face_tets;
  static const int face_of[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (const auto& f : face_of) {
      std::array<int, 3> key{mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
      std::sort(key.begin(), key.end());
      face_tets[key].push_back(static_cast<int>(t));
    }
  }
  s.regions.resize(static_cast<std::size_t>(nv));
  s.normal.assign(static_cast<std::size_t>(nv), Eigen::Vector3d::Zero());
  for (Eigen::Index v = 0; v < nv; ++v)
    for (const int t : s.star[static_cast<std::size_t>(v)])
      s.regions[static_cast<std::size_t>(v)].insert(mesh.subdomains[t]);
  for (const auto& [key, tets] : face_tets) {
    const int inside = mesh.subdomains[tets[0]];
    const int other = tets.size() == 1 ? -1 : mesh.subdomains[tets[1]];
    if (inside == other) continue;
    // The face's normal pointing out of tets[0] (away from its fourth vertex).
    const Eigen::Vector3d a = mesh.vertices.row(key[0]), b = mesh.vertices.row(key[1]),
                          c = mesh.vertices.row(key[2]);
    Eigen::Vector3d n = 0.5 * (b - a).cross(c - a);
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k)
      centroid += 0.25 * mesh.vertices.row(mesh.tets(tets[0], k)).transpose();
    if (n.dot(a - centroid) < 0.0) n = -n;
    if (inside > other) n = -n; // from the smaller label to the larger
    for (const int v : key) {
      s.regions[static_cast<std::size_t>(v)].insert(other);
      s.normal[static_cast<std::size_t>(v)] += n;
    }
  }
  return s;
}

/// The vertices of the tets with an angle under bound_deg, in index order.
std::set<int> sliver_vertices(const TetMesh& mesh, double bound_deg) {
  std::set<int> vertices;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
    if (*std::min_element(angles.begin(), angles.end()) < bound_deg)
      for (int k = 0; k < 4; ++k)
        vertices.insert(mesh.tets(t, k));
  }
  return vertices;
}

/// The directions in which vertex v (at x) is tried: 26 around a free vertex; 12 in the tangent
/// plane (normal n) of an interface vertex. Both also try, for each sliver of the vertex, the way
/// straight off the face opposite it (the one that thickens that sliver), within the tangent plane
/// for an interface vertex.
std::vector<Eigen::Vector3d> move_directions(const TetMesh& mesh, int v, const Eigen::Vector3d& x,
                                             const std::vector<int>& star, bool interface,
                                             const Eigen::Vector3d& n, double bound_deg) {
  std::vector<Eigen::Vector3d> directions;
  if (!interface) {
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          if (i || j || k) directions.push_back(Eigen::Vector3d(i, j, k).normalized());
  } else {
    const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
    for (int d = 0; d < 12; ++d) {
      const double angle = 2.0 * M_PI * d / 12.0;
      directions.push_back(std::cos(angle) * u + std::sin(angle) * w);
    }
  }
  for (const int t : star) {
    const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
    if (!(*std::min_element(angles.begin(), angles.end()) < bound_deg)) continue;
    Eigen::Vector3d p[3];
    int m = 0;
    for (int k = 0; k < 4; ++k)
      if (mesh.tets(t, k) != v) p[m++] = mesh.vertices.row(mesh.tets(t, k)).transpose();
    Eigen::Vector3d off = (p[1] - p[0]).cross(p[2] - p[0]);
    if (off.dot(x - p[0]) < 0.0) off = -off;
    if (interface) off -= off.dot(n) * n;
    if (off.norm() > 0.0) directions.push_back(off.normalized());
  }
  return directions;
}

/// Moves vertex v where the smallest angle of its tets is largest (on its interface when it lies
/// on one); true when it moved.
bool improve_vertex(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label, double bound_deg,
                    const VertexSurroundings& s, int v) {
  const auto vi = static_cast<std::size_t>(v);
  const std::set<int>& around = s.regions[vi];
  if (around.size() > 2) return false; // where three regions meet (or a region meets two and the outside)
  const std::vector<int>& star = s.star[vi];
  const Eigen::Vector3d x = mesh.vertices.row(v).transpose();
  double reach = 0.0; // mean length of the vertex's edges
  int edges = 0;
  for (const int t : star)
    for (int k = 0; k < 4; ++k)
      if (mesh.tets(t, k) != v) {
        reach += (mesh.vertices.row(mesh.tets(t, k)).transpose() - x).norm();
        ++edges;
      }
  reach /= std::max(1, edges);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  if (around.size() != 1) {
    if (!(s.normal[vi].norm() > 0.0)) return false;
    n = s.normal[vi].normalized();
  }
  const std::vector<Eigen::Vector3d> directions =
      move_directions(mesh, v, x, star, around.size() != 1, n, bound_deg);
  const int below = *around.begin(), above = *around.rbegin();
  std::vector<bool> in_subdomain;
  for (const int t : star)
    in_subdomain.push_back(centroid_in_subdomain(mesh, t, label));
  int slivers_at_x = 0, slivers = 0;
  double best =
      star_quality(mesh, star, in_subdomain, v, x, label, std::min(bound_deg, k_sliver_deg), slivers_at_x);
  Eigen::Vector3d best_x = x;
  for (const double step : {0.05, 0.1, 0.2, 0.35}) {
    for (const Eigen::Vector3d& d : directions) {
      Eigen::Vector3d candidate = x + step * reach * d;
      if (around.size() == 2) {
        // Back onto the interface: bisection along the normal between the two regions.
        double lo = -0.5 * reach, hi = 0.5 * reach;
        if (label(candidate + lo * n) != below || label(candidate + hi * n) != above) continue;
        for (int i = 0; i < 30; ++i) {
          const double mid = 0.5 * (lo + hi);
          (label(candidate + mid * n) == below ? lo : hi) = mid;
        }
        candidate += 0.5 * (lo + hi) * n;
      }
      // A move may not leave more slivers around the vertex than it found, only better ones.
      const double q = star_quality(mesh, star, in_subdomain, v, candidate, label,
                                    std::min(bound_deg, k_sliver_deg), slivers);
      if (q > best + 1e-9 && slivers <= slivers_at_x) {
        best = q;
        best_x = candidate;
      }
    }
  }
  if (best_x == x) return false;
  mesh.vertices.row(v) = best_x.transpose();
  return true;
}

} // namespace

int improve_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label, double bound_deg,
                    int passes) {
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  const VertexSurroundings surroundings = vertex_surroundings(mesh);
  int moved = 0;
  for (int pass = 0; pass < passes; ++pass) {
    const std::set<int> vertices = sliver_vertices(mesh, bound_deg); // of the slivers, in index order
    if (vertices.empty()) break;
    int moved_in_pass = 0;
    for (const int v : vertices)
      if (improve_vertex(mesh, label, bound_deg, surroundings, v)) ++moved_in_pass;
    moved += moved_in_pass;
    if (moved_in_pass == 0) break;
  }
  return moved;
}

} // namespace phantasm
