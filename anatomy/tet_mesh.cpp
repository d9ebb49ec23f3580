// Tet meshes of solid organs apart from the CGAL mesher (tet_mesh_cgal.cpp) and the sliver
// repairs (sliver_*.cpp): the meshing criteria, the innermost of nested shapes, the faces between
// subdomains, the tets' groups for the bulk constraints and the boundary as a surface.

#include "anatomy/tet_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace phantasm {

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

} // namespace phantasm
