#include "anatomy/tet_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
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

TetMeshCriteria criteria_for_tet_size(double tet_size_mm) {
  TetMeshCriteria criteria;
  criteria.cell_size_mm = tet_size_mm;
  // Interfaces between tissues are meshed as surfaces: their triangles as large as the tets, and
  // close enough to the surface (a tenth of the size, as for the organs' own meshes) that a layer
  // thinner than a tet keeps its thickness.
  criteria.facet_size_mm = tet_size_mm;
  criteria.facet_distance_mm = 0.1 * tet_size_mm;
  return criteria;
}

int NestedShapes::innermost(const Eigen::Vector3d& x) const {
  if (shapes.empty() || shapes[0]->value(x) <= 0.0) return -1;
  int current = 0;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (std::size_t k = 1; k < shapes.size(); ++k) {
      if (parent[k] == current && shapes[k]->value(x) > 0.0) {
        current = static_cast<int>(k);
        deeper = true;
        break;
      }
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

double tet_volume(const TetMesh& mesh, Eigen::Index t) {
  const Eigen::Vector3d a = mesh.vertices.row(mesh.tets(t, 0)).transpose();
  const Eigen::Vector3d b = mesh.vertices.row(mesh.tets(t, 1)).transpose();
  const Eigen::Vector3d c = mesh.vertices.row(mesh.tets(t, 2)).transpose();
  const Eigen::Vector3d d = mesh.vertices.row(mesh.tets(t, 3)).transpose();
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

std::array<double, 6> tet_dihedral_angles_deg(const TetMesh& mesh, Eigen::Index t) {
  Eigen::Vector3d p[4];
  for (int k = 0; k < 4; ++k)
    p[k] = mesh.vertices.row(mesh.tets(t, k)).transpose();
  // Outward face normals; face k is opposite vertex k.
  Eigen::Vector3d n[4];
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d a = p[(k + 1) % 4], b = p[(k + 2) % 4], c = p[(k + 3) % 4];
    n[k] = (b - a).cross(c - a).normalized();
    if (n[k].dot(p[k] - a) > 0.0) n[k] = -n[k];
  }
  std::array<double, 6> angles;
  int i = 0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      // The dihedral angle at the edge shared by faces a and b is pi minus the angle of their normals.
      angles[static_cast<std::size_t>(i++)] =
          180.0 - std::acos(std::clamp(n[a].dot(n[b]), -1.0, 1.0)) * 180.0 / M_PI;
    }
  }
  return angles;
}

double min_dihedral_angle_deg(const TetMesh& mesh) {
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (double angle : tet_dihedral_angles_deg(mesh, t))
      smallest = std::min(smallest, angle);
  }
  return smallest;
}

double mean_edge_length(const TetMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        edges.emplace_back(std::minmax(mesh.tets(t, a), mesh.tets(t, b)));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  double sum = 0.0;
  for (const auto& [a, b] : edges)
    sum += (mesh.vertices.row(a) - mesh.vertices.row(b)).norm();
  return edges.empty() ? 0.0 : sum / static_cast<double>(edges.size());
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
