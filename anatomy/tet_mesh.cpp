#include "anatomy/tet_mesh.hpp"

#include "geometry/tet_quality.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace phantasm {
namespace {

/// A tet with a dihedral angle under this is counted as a sliver (the log's "tets under 10 deg"):
/// the repairs may raise the smallest angle of the tets they change, but not leave more slivers.
constexpr double k_sliver_deg = 10.0;

} // namespace

TetMeshCriteria criteria_for_boundary_size(double surface_area_mm2, int boundary_triangles) {
  // An equilateral triangle of edge s has area (sqrt(3)/4) s^2 and circumradius s / sqrt(3).
  // Mesh_3's facets come out about 1.35 times smaller than the bound (measured on ellipsoids).
  const double edge =
      1.35 * std::sqrt(surface_area_mm2 / (0.25 * std::sqrt(3.0) * std::max(1, boundary_triangles)));
  TetMeshCriteria criteria;
  criteria.facet_size_mm = edge / std::sqrt(3.0);
  criteria.facet_distance_mm = 0.1 * edge;
  criteria.cell_size_mm = edge;
  return criteria;
}

TetMeshCriteria criteria_for_tet_size(double tet_size_mm, double facet_distance_mm) {
  TetMeshCriteria criteria;
  criteria.cell_size_mm = tet_size_mm;
  // Interfaces between tissues are meshed as surfaces: their triangles as large as the tets, and
  // close enough to the surface (a tenth of the size, as for the organs' own meshes) that a layer
  // thinner than a tet keeps its thickness. The scene may give a coarser distance for a folded
  // surface (a cortex), which followed within a tenth of the tet size needs far more triangles
  // than tets of that size would.
  criteria.facet_size_mm = tet_size_mm;
  criteria.facet_distance_mm = facet_distance_mm > 0.0 ? facet_distance_mm : 0.1 * tet_size_mm;
  return criteria;
}

int NestedShapes::innermost(const Eigen::Vector3d& x) const {
  double value = shapes.empty() ? 0.0 : shapes[0]->value(x);
  if (value <= 0.0) return -1;
  int current = 0;
  for (bool deeper = true; deeper;) {
    deeper = false;
    // Smoothed indicators: the share of the current shape left to its own region, and the child
    // of the largest indicator.
    double own_share = value + 0.5;
    bool indicators = shapes[static_cast<std::size_t>(current)]->smoothed_indicator();
    int best = -1;
    double best_value = 0.0;
    for (std::size_t k = 1; k < shapes.size() && !deeper; ++k) {
      if (parent[k] != current) continue;
      const double v = shapes[k]->value(x);
      if (v > 0.0) {
        current = static_cast<int>(k);
        value = v;
        deeper = true;
      }
      indicators = indicators && shapes[k]->smoothed_indicator();
      own_share -= v + 0.5;
      if (best < 0 || v > best_value) {
        best = static_cast<int>(k);
        best_value = v;
      }
    }
    // Outside every child. Smoothed labels that touch leave a sliver between them where each
    // child's indicator is just under 1/2 while their container's own share is near 0: the
    // point belongs to the child that holds most of it (the labels' argmax), so that the
    // children share a face instead of a layer of the container as thin as the mesher's
    // tolerance (which it would refine without end).
    if (!deeper && indicators && best >= 0 && best_value + 0.5 > own_share) {
      current = best;
      value = best_value;
      deeper = true;
    }
  }
  return current;
}

Eigen::MatrixX3i subdomain_interface_faces(const TetMesh& mesh) {
  // Each face by its sorted vertices: the first tet seen with it and that tet's opposite vertex.
  std::map<std::array<int, 3>, std::pair<Eigen::Index, int>> first;
  std::vector<Eigen::Vector3i> faces;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key;
      for (int j = 0, m = 0; j < 4; ++j)
        if (j != k) key[static_cast<std::size_t>(m++)] = mesh.tets(t, j);
      std::sort(key.begin(), key.end());
      const auto [found, inserted] = first.emplace(key, std::make_pair(t, k));
      if (inserted) continue;
      const Eigen::Index other = found->second.first;
      if (mesh.subdomains[other] == mesh.subdomains[t]) continue;
      // Oriented outward of the tet of the smaller subdomain index.
      const Eigen::Index inner = mesh.subdomains[other] < mesh.subdomains[t] ? other : t;
      const int opposite = inner == other ? found->second.second : k;
      Eigen::Vector3i f(key[0], key[1], key[2]);
      const Eigen::Vector3d a = mesh.vertices.row(f[0]).transpose();
      const Eigen::Vector3d normal =
          (mesh.vertices.row(f[1]).transpose() - a).cross(mesh.vertices.row(f[2]).transpose() - a);
      if (normal.dot(mesh.vertices.row(mesh.tets(inner, opposite)).transpose() - a) > 0.0)
        std::swap(f[1], f[2]);
      faces.push_back(f);
    }
  }
  Eigen::MatrixX3i result(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i)
    result.row(static_cast<Eigen::Index>(i)) = faces[i].transpose();
  return result;
}

std::vector<std::vector<int>> group_tets(const TetMesh& mesh, int target_size,
                                         const std::vector<int>& labels) {
  const auto n = static_cast<std::size_t>(mesh.tets.rows());
  target_size = std::max(1, target_size);
  std::vector<int> label(n, 0);
  if (labels.size() == n) {
    label = labels;
  } else if (static_cast<std::size_t>(mesh.subdomains.size()) == n) {
    for (std::size_t t = 0; t < n; ++t)
      label[t] = mesh.subdomains[static_cast<Eigen::Index>(t)];
  }
  // Face neighbours of the same label (at most 4 per tet).
  std::vector<std::array<int, 4>> neighbours(n, {-1, -1, -1, -1});
  {
    std::vector<std::pair<std::array<int, 3>, int>> faces;
    faces.reserve(4 * n);
    for (std::size_t t = 0; t < n; ++t) {
      for (int skip = 0; skip < 4; ++skip) {
        std::array<int, 3> f{};
        for (int k = 0, j = 0; k < 4; ++k)
          if (k != skip) f[static_cast<std::size_t>(j++)] = mesh.tets(static_cast<Eigen::Index>(t), k);
        std::sort(f.begin(), f.end());
        faces.emplace_back(f, static_cast<int>(t));
      }
    }
    std::sort(faces.begin(), faces.end());
    std::vector<int> used(n, 0);
    for (std::size_t i = 0; i + 1 < faces.size(); ++i) {
      if (faces[i].first != faces[i + 1].first) continue;
      const int a = faces[i].second, b = faces[i + 1].second;
      if (label[static_cast<std::size_t>(a)] != label[static_cast<std::size_t>(b)]) continue;
      neighbours[static_cast<std::size_t>(a)][static_cast<std::size_t>(used[static_cast<std::size_t>(a)]++)] =
          b;
      neighbours[static_cast<std::size_t>(b)][static_cast<std::size_t>(used[static_cast<std::size_t>(b)]++)] =
          a;
    }
  }
  std::vector<Eigen::Vector3d> centroid(n, Eigen::Vector3d::Zero());
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 4; ++k)
      centroid[t] += 0.25 * mesh.vertices.row(mesh.tets(static_cast<Eigen::Index>(t), k)).transpose();
  std::vector<int> group_of(n, -1);
  // Seeds: the ungrouped tet with the fewest ungrouped neighbours, then the smallest index.
  std::vector<int> free_neighbours(n, 0);
  std::set<std::pair<int, int>> seeds;
  for (std::size_t t = 0; t < n; ++t) {
    for (int u : neighbours[t])
      if (u >= 0) ++free_neighbours[t];
    seeds.emplace(free_neighbours[t], static_cast<int>(t));
  }
  auto take = [&](int t, int group) {
    seeds.erase({free_neighbours[static_cast<std::size_t>(t)], t});
    group_of[static_cast<std::size_t>(t)] = group;
    for (int u : neighbours[static_cast<std::size_t>(t)]) {
      if (u < 0 || group_of[static_cast<std::size_t>(u)] >= 0) continue;
      seeds.erase({free_neighbours[static_cast<std::size_t>(u)], u});
      seeds.emplace(--free_neighbours[static_cast<std::size_t>(u)], u);
    }
  };
  std::vector<std::vector<int>> groups;
  while (!seeds.empty()) {
    const int group = static_cast<int>(groups.size());
    std::vector<int> members = {seeds.begin()->second};
    take(members[0], group);
    Eigen::Vector3d center = centroid[static_cast<std::size_t>(members[0])];
    while (static_cast<int>(members.size()) < target_size) {
      // The best ungrouped neighbour: most faces shared with the group, then closest, then first.
      int best = -1, best_shared = 0;
      double best_distance = 0.0;
      for (int m : members) {
        for (int u : neighbours[static_cast<std::size_t>(m)]) {
          if (u < 0 || group_of[static_cast<std::size_t>(u)] >= 0) continue;
          int shared = 0;
          for (int w : neighbours[static_cast<std::size_t>(u)])
            if (w >= 0 && group_of[static_cast<std::size_t>(w)] == group) ++shared;
          const double distance = (centroid[static_cast<std::size_t>(u)] - center).squaredNorm();
          if (best < 0 || shared > best_shared || (shared == best_shared && distance < best_distance) ||
              (shared == best_shared && distance == best_distance && u < best)) {
            best = u;
            best_shared = shared;
            best_distance = distance;
          }
        }
      }
      if (best < 0) break;
      take(best, group);
      members.push_back(best);
      center = (center * static_cast<double>(members.size() - 1) + centroid[static_cast<std::size_t>(best)]) /
               static_cast<double>(members.size());
    }
    groups.push_back(std::move(members));
  }
  // Small leftovers join the smallest neighbouring group (of the same label, by adjacency).
  const auto small = static_cast<std::size_t>(std::max(1, target_size / 2));
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (groups[g].empty() || groups[g].size() >= small) continue;
    int into = -1;
    for (int t : groups[g])
      for (int u : neighbours[static_cast<std::size_t>(t)]) {
        if (u < 0) continue;
        const int h = group_of[static_cast<std::size_t>(u)];
        if (h == static_cast<int>(g)) continue;
        if (into < 0 ||
            groups[static_cast<std::size_t>(h)].size() < groups[static_cast<std::size_t>(into)].size() ||
            (groups[static_cast<std::size_t>(h)].size() == groups[static_cast<std::size_t>(into)].size() &&
             h < into))
          into = h;
      }
    if (into < 0) continue; // an isolated piece: it stays a group of its own
    for (int t : groups[g]) {
      group_of[static_cast<std::size_t>(t)] = into;
      groups[static_cast<std::size_t>(into)].push_back(t);
    }
    groups[g].clear();
  }
  groups.erase(
      std::remove_if(groups.begin(), groups.end(), [](const std::vector<int>& g) { return g.empty(); }),
      groups.end());
  return groups;
}

TriangleMesh boundary_surface(const TetMesh& mesh, Eigen::VectorXi* tet_vertex_of_surface_vertex) {
  Eigen::VectorXi surface_index = Eigen::VectorXi::Constant(mesh.vertices.rows(), -1);
  std::vector<int> tet_vertex;
  TriangleMesh surface;
  surface.faces.resize(mesh.boundary_faces.rows(), 3);
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.boundary_faces(f, k);
      if (surface_index[v] < 0) {
        surface_index[v] = static_cast<int>(tet_vertex.size());
        tet_vertex.push_back(v);
      }
      surface.faces(f, k) = surface_index[v];
    }
  }
  surface.vertices.resize(static_cast<Eigen::Index>(tet_vertex.size()), 3);
  for (std::size_t i = 0; i < tet_vertex.size(); ++i) {
    surface.vertices.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(tet_vertex[i]);
  }
  if (tet_vertex_of_surface_vertex) {
    *tet_vertex_of_surface_vertex =
        Eigen::Map<Eigen::VectorXi>(tet_vertex.data(), static_cast<Eigen::Index>(tet_vertex.size()));
  }
  return surface;
}

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

} // namespace

int improve_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label, double bound_deg,
                    int passes) {
  const Eigen::Index nv = mesh.vertices.rows();
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  std::vector<std::vector<int>> star(static_cast<std::size_t>(nv));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  // The regions around each vertex (-1: outside, for vertices of the boundary) and, on an
  // interface of two regions, the interface's normal (area-weighted, from the smaller label's
  // side to the larger's).
  std::map<std::array<int, 3>, std::vector<int>> face_tets;
  static const int face_of[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (const auto& f : face_of) {
      std::array<int, 3> key{mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
      std::sort(key.begin(), key.end());
      face_tets[key].push_back(static_cast<int>(t));
    }
  }
  std::vector<std::set<int>> regions(static_cast<std::size_t>(nv));
  std::vector<Eigen::Vector3d> normal(static_cast<std::size_t>(nv), Eigen::Vector3d::Zero());
  for (Eigen::Index v = 0; v < nv; ++v)
    for (const int t : star[static_cast<std::size_t>(v)])
      regions[static_cast<std::size_t>(v)].insert(mesh.subdomains[t]);
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
      regions[static_cast<std::size_t>(v)].insert(other);
      normal[static_cast<std::size_t>(v)] += n;
    }
  }
  int moved = 0;
  for (int pass = 0; pass < passes; ++pass) {
    std::set<int> vertices; // of the slivers, in index order
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
      if (*std::min_element(angles.begin(), angles.end()) < bound_deg)
        for (int k = 0; k < 4; ++k)
          vertices.insert(mesh.tets(t, k));
    }
    if (vertices.empty()) break;
    int moved_in_pass = 0;
    for (const int v : vertices) {
      const auto vi = static_cast<std::size_t>(v);
      const std::set<int>& around = regions[vi];
      if (around.size() > 2) continue; // where three regions meet (or a region meets two and the outside)
      const Eigen::Vector3d x = mesh.vertices.row(v).transpose();
      double reach = 0.0; // mean length of the vertex's edges
      int edges = 0;
      for (const int t : star[vi])
        for (int k = 0; k < 4; ++k)
          if (mesh.tets(t, k) != v) {
            reach += (mesh.vertices.row(mesh.tets(t, k)).transpose() - x).norm();
            ++edges;
          }
      reach /= std::max(1, edges);
      // Directions: 26 around a free vertex; 12 in the tangent plane of an interface vertex. Both
      // also try, for each sliver of the vertex, the way straight off the face opposite it (the
      // one that thickens that sliver), within the tangent plane for an interface vertex.
      std::vector<Eigen::Vector3d> directions;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      if (around.size() == 1) {
        for (int i = -1; i <= 1; ++i)
          for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k)
              if (i || j || k) directions.push_back(Eigen::Vector3d(i, j, k).normalized());
      } else {
        if (!(normal[vi].norm() > 0.0)) continue;
        n = normal[vi].normalized();
        const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
        for (int d = 0; d < 12; ++d) {
          const double angle = 2.0 * M_PI * d / 12.0;
          directions.push_back(std::cos(angle) * u + std::sin(angle) * w);
        }
      }
      for (const int t : star[vi]) {
        const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, t);
        if (!(*std::min_element(angles.begin(), angles.end()) < bound_deg)) continue;
        Eigen::Vector3d p[3];
        int m = 0;
        for (int k = 0; k < 4; ++k)
          if (mesh.tets(t, k) != v) p[m++] = mesh.vertices.row(mesh.tets(t, k)).transpose();
        Eigen::Vector3d off = (p[1] - p[0]).cross(p[2] - p[0]);
        if (off.dot(x - p[0]) < 0.0) off = -off;
        if (around.size() == 2) off -= off.dot(n) * n;
        if (off.norm() > 0.0) directions.push_back(off.normalized());
      }
      const int below = *around.begin(), above = *around.rbegin();
      std::vector<bool> in_subdomain;
      for (const int t : star[vi])
        in_subdomain.push_back(centroid_in_subdomain(mesh, t, label));
      int slivers_at_x = 0, slivers = 0;
      double best = star_quality(mesh, star[vi], in_subdomain, v, x, label, std::min(bound_deg, k_sliver_deg),
                                 slivers_at_x);
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
          const double q = star_quality(mesh, star[vi], in_subdomain, v, candidate, label,
                                        std::min(bound_deg, k_sliver_deg), slivers);
          if (q > best + 1e-9 && slivers <= slivers_at_x) {
            best = q;
            best_x = candidate;
          }
        }
      }
      if (best_x != x) {
        mesh.vertices.row(v) = best_x.transpose();
        ++moved_in_pass;
      }
    }
    moved += moved_in_pass;
    if (moved_in_pass == 0) break;
  }
  return moved;
}

} // namespace phantasm

namespace phantasm {
namespace {

/// The faces of a positively oriented tet, each opposite one vertex, oriented outward.
constexpr int k_outward_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

using FaceKey = std::array<int, 3>;

/// The face of `tet` opposite its vertex `opposite`, its vertices sorted.
FaceKey face_key(const Eigen::Vector4i& tet, int opposite) {
  FaceKey key{tet[k_outward_face[opposite][0]], tet[k_outward_face[opposite][1]],
              tet[k_outward_face[opposite][2]]};
  std::sort(key.begin(), key.end());
  return key;
}

FaceKey face_key(const TetMesh& mesh, Eigen::Index t, int opposite) {
  return face_key(Eigen::Vector4i(mesh.tets.row(t).transpose()), opposite);
}

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

namespace phantasm {

int flip_slivers(TetMesh& mesh, double bound_deg, int passes) {
  const bool labelled = mesh.subdomains.size() == mesh.tets.rows();
  std::vector<Eigen::Vector4i> tets;
  std::vector<int> region;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    tets.push_back(mesh.tets.row(t).transpose());
    region.push_back(labelled ? mesh.subdomains[t] : 0);
  }
  std::vector<char> alive(tets.size(), 1);
  std::map<FaceKey, std::vector<int>> faces;
  std::vector<std::vector<int>> star(static_cast<std::size_t>(mesh.vertices.rows()));
  const auto enter = [&](int t) {
    for (int k = 0; k < 4; ++k) {
      faces[face_key(tets[static_cast<std::size_t>(t)], k)].push_back(t);
      star[static_cast<std::size_t>(tets[static_cast<std::size_t>(t)][k])].push_back(t);
    }
  };
  const auto leave = [&](int t) {
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = face_key(tets[static_cast<std::size_t>(t)], k);
      std::vector<int>& around = faces[key];
      around.erase(std::find(around.begin(), around.end(), t));
      if (around.empty()) faces.erase(key);
      std::vector<int>& at = star[static_cast<std::size_t>(tets[static_cast<std::size_t>(t)][k])];
      at.erase(std::find(at.begin(), at.end(), t));
    }
  };
  for (std::size_t t = 0; t < tets.size(); ++t)
    enter(static_cast<int>(t));
  const auto volume = [&](const Eigen::Vector4i& tet) {
    const std::array<Eigen::Vector3d, 4> p = tet_corners(mesh, tet);
    return signed_volume(p[0], p[1], p[2], p[3]);
  };
  const auto quality = [&](const Eigen::Vector4i& tet) {
    const std::array<double, 6> angles = dihedral_angles_deg(tet_corners(mesh, tet));
    return *std::min_element(angles.begin(), angles.end());
  };
  const auto oriented = [&](Eigen::Vector4i tet) {
    if (volume(tet) < 0.0) std::swap(tet[0], tet[1]);
    return tet;
  };
  struct Flip {
    std::vector<int> old;
    std::vector<Eigen::Vector4i> made;
    double gain = 0.0; ///< smallest angle of the new tets less that of the old, degrees
  };
  // A flip is kept when its tets fill the old ones' volume (so none overlaps another or leaves a
  // gap), none is flat, and the smallest angle rises.
  const auto judge = [&](Flip& flip) {
    double before = 0.0, after = 0.0, old_quality = 180.0, new_quality = 180.0;
    int old_slivers = 0, new_slivers = 0;
    for (const int t : flip.old) {
      before += volume(tets[static_cast<std::size_t>(t)]);
      const double q = quality(tets[static_cast<std::size_t>(t)]);
      old_quality = std::min(old_quality, q);
      old_slivers += q < k_sliver_deg;
    }
    for (const Eigen::Vector4i& tet : flip.made) {
      const double v = volume(tet);
      if (!(v > 1e-9 * std::abs(before))) return false;
      after += v;
      const double q = quality(tet);
      new_quality = std::min(new_quality, q);
      new_slivers += q < k_sliver_deg;
    }
    if (!(std::abs(after - before) <= 1e-9 * std::abs(before)) || new_slivers > old_slivers) return false;
    flip.gain = new_quality - old_quality;
    return flip.gain > 1e-9;
  };
  const auto face_flip = [&](int t, int k, Flip& flip) { // 2-3
    const Eigen::Vector4i& tet = tets[static_cast<std::size_t>(t)];
    const FaceKey key = face_key(tet, k);
    const auto found = faces.find(key);
    if (found == faces.end() || found->second.size() != 2) return false;
    const int u = found->second[0] == t ? found->second[1] : found->second[0];
    if (region[static_cast<std::size_t>(u)] != region[static_cast<std::size_t>(t)]) return false;
    const int d = tet[k];
    int e = -1;
    for (int j = 0; j < 4; ++j)
      if (std::find(key.begin(), key.end(), tets[static_cast<std::size_t>(u)][j]) == key.end())
        e = tets[static_cast<std::size_t>(u)][j];
    flip.old = {t, u};
    flip.made.clear();
    for (int i = 0; i < 3; ++i)
      flip.made.push_back(oriented(Eigen::Vector4i(key[static_cast<std::size_t>(i)],
                                                   key[static_cast<std::size_t>((i + 1) % 3)], d, e)));
    return judge(flip);
  };
  // Edge removal: the n tets around an inner edge (a, b) (n from 3, the 3-2 flip, to 7) replaced
  // by the 2(n - 2) tets joining a and b to a fan triangulation of the ring of their other
  // vertices; the best of the n fans.
  const auto edge_flip = [&](int t, int a, int b, Flip& flip) {
    std::vector<int> ring;
    for (const int u : star[static_cast<std::size_t>(a)])
      if ((tets[static_cast<std::size_t>(u)].array() == b).any()) ring.push_back(u);
    if (ring.size() < 3 || ring.size() > 7) return false;
    std::map<int, std::vector<int>> holding; // ring vertex -> the ring's tets holding it
    for (const int u : ring) {
      if (region[static_cast<std::size_t>(u)] != region[static_cast<std::size_t>(t)]) return false;
      for (int j = 0; j < 4; ++j) {
        const int w = tets[static_cast<std::size_t>(u)][j];
        if (w != a && w != b) holding[w].push_back(u);
      }
    }
    // A closed ring: as many vertices as tets, each in two of them, each face around the edge
    // shared by two tets (inside, not boundary).
    if (holding.size() != ring.size()) return false;
    for (const auto& [w, held] : holding) {
      if (held.size() != 2) return false;
      FaceKey key{a, b, w};
      std::sort(key.begin(), key.end());
      const auto found = faces.find(key);
      if (found == faces.end() || found->second.size() != 2) return false;
    }
    // The ring's vertices in order around the edge.
    std::vector<int> polygon{holding.begin()->first};
    int through = holding.begin()->second[0];
    while (polygon.size() < ring.size()) {
      int next = -1;
      for (int j = 0; j < 4; ++j) {
        const int w = tets[static_cast<std::size_t>(through)][j];
        if (w != a && w != b && w != polygon.back()) next = w;
      }
      const std::vector<int>& held = holding[next];
      through = held[0] == through ? held[1] : held[0];
      polygon.push_back(next);
    }
    const auto n = static_cast<int>(polygon.size());
    bool found = false;
    Flip trial;
    trial.old = ring;
    for (int apex = 0; apex < n; ++apex) {
      trial.made.clear();
      for (int j = 1; j + 1 < n; ++j) {
        const int p = polygon[static_cast<std::size_t>(apex)],
                  q = polygon[static_cast<std::size_t>((apex + j) % n)],
                  r = polygon[static_cast<std::size_t>((apex + j + 1) % n)];
        trial.made.push_back(oriented(Eigen::Vector4i(p, q, r, a)));
        trial.made.push_back(oriented(Eigen::Vector4i(p, q, r, b)));
      }
      if (judge(trial) && (!found || trial.gain > flip.gain)) {
        flip = trial;
        found = true;
      }
      if (n == 3) break; // one triangle: every apex gives it
    }
    return found;
  };
  int flips = 0;
  for (int pass = 0; pass < passes; ++pass) {
    int flips_in_pass = 0;
    for (std::size_t t = 0; t < tets.size(); ++t) {
      if (!alive[t] || quality(tets[t]) >= bound_deg) continue;
      Flip best, candidate;
      for (int k = 0; k < 4; ++k)
        if (face_flip(static_cast<int>(t), k, candidate) && candidate.gain > best.gain) best = candidate;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          if (edge_flip(static_cast<int>(t), tets[t][i], tets[t][j], candidate) && candidate.gain > best.gain)
            best = candidate;
      if (best.made.empty()) continue;
      const int kept_region = region[t];
      for (const int u : best.old) {
        leave(u);
        alive[static_cast<std::size_t>(u)] = 0;
      }
      std::vector<int> slots = best.old; // reused first, in order; more are appended
      for (std::size_t m = 0; m < best.made.size(); ++m) {
        int slot;
        if (m < slots.size()) {
          slot = slots[m];
        } else {
          slot = static_cast<int>(tets.size());
          tets.emplace_back();
          region.push_back(kept_region);
          alive.push_back(0);
        }
        tets[static_cast<std::size_t>(slot)] = best.made[m];
        region[static_cast<std::size_t>(slot)] = kept_region;
        alive[static_cast<std::size_t>(slot)] = 1;
        enter(slot);
      }
      ++flips_in_pass;
    }
    flips += flips_in_pass;
    if (flips_in_pass == 0) break;
  }
  if (flips == 0) return 0;
  const auto count = static_cast<Eigen::Index>(std::count(alive.begin(), alive.end(), 1));
  mesh.tets.resize(count, 4);
  if (labelled) mesh.subdomains.resize(count);
  Eigen::Index next = 0;
  for (std::size_t t = 0; t < tets.size(); ++t) {
    if (!alive[t]) continue;
    mesh.tets.row(next) = tets[t].transpose();
    if (labelled) mesh.subdomains[next] = region[t];
    ++next;
  }
  return flips;
}

} // namespace phantasm

namespace phantasm {

int split_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label) {
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  std::vector<std::vector<int>> star(static_cast<std::size_t>(mesh.vertices.rows()));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  const auto smallest = [](const std::array<Eigen::Vector3d, 4>& p) {
    const std::array<double, 6> angles = dihedral_angles_deg(p);
    return *std::min_element(angles.begin(), angles.end());
  };
  // A split of the edge (p, q): the ring's tets with q replaced by the new vertex, then with p.
  struct Split {
    int p = -1, q = -1;
    std::vector<int> ring;
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    double gain = 0.0;
  };
  const auto corners_with = [&](int t, int from, const Eigen::Vector3d& x) {
    std::array<Eigen::Vector3d, 4> c;
    for (int k = 0; k < 4; ++k)
      c[static_cast<std::size_t>(k)] =
          mesh.tets(t, k) == from ? x : Eigen::Vector3d(mesh.vertices.row(mesh.tets(t, k)).transpose());
    return c;
  };
  const auto centroid_of = [](const std::array<Eigen::Vector3d, 4>& c) {
    return 0.25 * (c[0] + c[1] + c[2] + c[3]);
  };
  const auto try_edge = [&](int t, int p, int q, Split& split) {
    std::vector<int> ring;
    for (const int u : star[static_cast<std::size_t>(p)])
      if ((mesh.tets.row(u).array() == q).any()) ring.push_back(u);
    std::map<int, std::vector<int>> holding; // ring vertex -> the ring's tets holding it
    std::set<int> regions;
    for (const int u : ring) {
      regions.insert(mesh.subdomains[u]);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(u, k) != p && mesh.tets(u, k) != q) holding[mesh.tets(u, k)].push_back(u);
    }
    // The faces around the edge that separate two sides: boundary faces (one tet) and faces
    // between regions. None: the edge lies inside one region and the new vertex is free. Two,
    // and two sides: the edge lies on that surface and the new vertex stays on it. Else: no split.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); // from the lower label's side to the upper's
    int separating = 0;
    for (const auto& [w, held] : holding) {
      if (held.size() > 2) return false;
      const int u = held[0];
      const int other = held.size() == 2 ? mesh.subdomains[held[1]] : -1;
      if (other == mesh.subdomains[u]) continue;
      ++separating;
      const Eigen::Vector3d x0 = mesh.vertices.row(p), x1 = mesh.vertices.row(q), x2 = mesh.vertices.row(w);
      Eigen::Vector3d n = (x1 - x0).cross(x2 - x0);
      Eigen::Vector3d apex = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(u, k) != p && mesh.tets(u, k) != q && mesh.tets(u, k) != w)
          apex = mesh.vertices.row(mesh.tets(u, k)).transpose();
      if (n.dot(apex - x0) > 0.0) n = -n;     // out of u
      if (mesh.subdomains[u] > other) n = -n; // from the lower label to the upper
      normal += n;
    }
    int lower = mesh.subdomains[t], upper = lower;
    if (separating == 0) {
      if (ring.size() < 3 || regions.size() != 1) return false;
    } else {
      if (separating != 2 || !(normal.norm() > 0.0)) return false;
      std::set<int> sides = regions;
      if (holding.size() != ring.size()) sides.insert(-1); // an open ring: the boundary
      if (sides.size() != 2) return false;
      lower = *sides.begin();
      upper = *sides.rbegin();
      normal.normalize();
    }
    double old_quality = 180.0;
    int old_slivers = 0;
    for (const int u : ring) {
      const double angle = smallest(corners_with(u, -1, Eigen::Vector3d::Zero()));
      old_quality = std::min(old_quality, angle);
      old_slivers += angle < k_sliver_deg;
    }
    const Eigen::Vector3d a = mesh.vertices.row(p).transpose(), b = mesh.vertices.row(q).transpose();
    const Eigen::Vector3d middle = 0.5 * (a + b);
    const double length = (b - a).norm();
    std::vector<Eigen::Vector3d> directions;
    if (separating == 0) {
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k)
            if (i || j || k) directions.push_back(Eigen::Vector3d(i, j, k).normalized());
    } else {
      const Eigen::Vector3d u = normal.unitOrthogonal(), w = normal.cross(u);
      for (int d = 0; d < 12; ++d)
        directions.push_back(std::cos(2.0 * M_PI * d / 12.0) * u + std::sin(2.0 * M_PI * d / 12.0) * w);
    }
    const std::array<Eigen::Vector3d, 4> c = corners_with(t, -1, Eigen::Vector3d::Zero());
    for (int k = 0; k < 4; ++k) { // off the sliver's faces (within the surface for a surface edge)
      const Eigen::Vector3d o = c[static_cast<std::size_t>((k + 1) % 4)];
      Eigen::Vector3d n =
          (c[static_cast<std::size_t>((k + 2) % 4)] - o).cross(c[static_cast<std::size_t>((k + 3) % 4)] - o);
      if (separating > 0) n -= n.dot(normal) * normal;
      if (n.norm() > 0.0) {
        directions.push_back(n.normalized());
        directions.push_back(-n.normalized());
      }
    }
    // Onto the surface: bisection along the normal between its two sides.
    const auto onto = [&](Eigen::Vector3d& x) {
      if (separating == 0) return true;
      double lo = -0.5 * length, hi = 0.5 * length;
      if (label(x + lo * normal) != lower || label(x + hi * normal) != upper) return false;
      for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (lo + hi);
        (label(x + mid * normal) == lower ? lo : hi) = mid;
      }
      x += 0.5 * (lo + hi) * normal;
      return true;
    };
    bool found = false;
    for (const double step : {0.0, 0.05, 0.1, 0.2, 0.35, 0.5}) {
      for (const Eigen::Vector3d& d : directions) {
        Eigen::Vector3d x = middle + step * length * d;
        if (!onto(x)) continue;
        double quality = 180.0;
        int slivers = 0;
        bool valid = true;
        for (const int u : ring) {
          for (const int from : {q, p}) {
            const std::array<Eigen::Vector3d, 4> cut = corners_with(u, from, x);
            if (!(signed_volume(cut[0], cut[1], cut[2], cut[3]) > 0.0) ||
                label(centroid_of(cut)) != mesh.subdomains[u]) {
              valid = false;
              break;
            }
            const double angle = smallest(cut);
            quality = std::min(quality, angle);
            slivers += angle < k_sliver_deg;
          }
          if (!valid) break;
        }
        if (!valid || slivers > old_slivers || !(quality - old_quality > 1e-9)) continue;
        if (!found || quality - old_quality > split.gain) {
          split = Split{p, q, ring, x, quality - old_quality};
          found = true;
        }
        if (step == 0.0) break; // the midpoint: one position, whatever the direction
      }
    }
    return found;
  };
  int splits = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (!(smallest(corners_with(static_cast<int>(t), -1, Eigen::Vector3d::Zero())) < k_sliver_deg)) continue;
    Split best, candidate;
    bool any = false;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (try_edge(static_cast<int>(t), mesh.tets(t, i), mesh.tets(t, j), candidate) &&
            (!any || candidate.gain > best.gain)) {
          best = candidate;
          any = true;
        }
    if (!any) continue;
    const int m = static_cast<int>(mesh.vertices.rows());
    mesh.vertices.conservativeResize(m + 1, 3);
    mesh.vertices.row(m) = best.at.transpose();
    star.emplace_back();
    const auto first_new = static_cast<int>(mesh.tets.rows());
    mesh.tets.conservativeResize(first_new + static_cast<Eigen::Index>(best.ring.size()), 4);
    mesh.subdomains.conservativeResize(mesh.tets.rows());
    for (std::size_t r = 0; r < best.ring.size(); ++r) {
      const int u = best.ring[r], w = first_new + static_cast<int>(r);
      mesh.tets.row(w) = mesh.tets.row(u);
      mesh.subdomains[w] = mesh.subdomains[u];
      for (int k = 0; k < 4; ++k) {
        if (mesh.tets(u, k) == best.q) mesh.tets(u, k) = m; // u keeps p
        if (mesh.tets(w, k) == best.p) mesh.tets(w, k) = m; // w keeps q
      }
      std::vector<int>& at_q = star[static_cast<std::size_t>(best.q)];
      *std::find(at_q.begin(), at_q.end(), u) = w;
      star[static_cast<std::size_t>(m)].push_back(u);
      star[static_cast<std::size_t>(m)].push_back(w);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(w, k) != m && mesh.tets(w, k) != best.q)
          star[static_cast<std::size_t>(mesh.tets(w, k))].push_back(w);
    }
    // Boundary triangles on the edge are cut in two at the new vertex, as the tets are.
    const Eigen::Index faces = mesh.boundary_faces.rows();
    for (Eigen::Index f = 0; f < faces; ++f) {
      const auto row = mesh.boundary_faces.row(f);
      if (!(row.array() == best.p).any() || !(row.array() == best.q).any()) continue;
      Eigen::RowVector3i second = row;
      for (int k = 0; k < 3; ++k) {
        if (mesh.boundary_faces(f, k) == best.q) mesh.boundary_faces(f, k) = m;
        if (second[k] == best.p) second[k] = m;
      }
      mesh.boundary_faces.conservativeResize(mesh.boundary_faces.rows() + 1, 3);
      mesh.boundary_faces.row(mesh.boundary_faces.rows() - 1) = second;
    }
    ++splits;
  }
  return splits;
}

} // namespace phantasm

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
