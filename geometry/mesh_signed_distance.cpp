// Closest points on a closed triangle mesh and the pseudonormal sign of the distance; see
// mesh_signed_distance.hpp.
#include "geometry/mesh_signed_distance.hpp"

#include "core/grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace phantasm {
namespace {

double box_distance_squared(const Eigen::Vector3d& x, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).squaredNorm();
}

std::vector<std::array<int, 3>> triangle_list(const Eigen::MatrixX3i& faces) {
  std::vector<std::array<int, 3>> triangles(static_cast<std::size_t>(faces.rows()));
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    triangles[static_cast<std::size_t>(t)] = {faces(t, 0), faces(t, 1), faces(t, 2)};
  return triangles;
}

} // namespace

SignedDistanceMesh::SignedDistanceMesh(std::vector<std::array<int, 3>> triangles)
    : m_triangles(std::move(triangles)) {
  connect();
}

SignedDistanceMesh::SignedDistanceMesh(const Eigen::MatrixX3i& faces) : m_triangles(triangle_list(faces)) {
  connect();
}

void SignedDistanceMesh::connect() {
  // Vertices numbered by first use, edges by their sorted vertex pair: the normals are summed
  // per vertex and per edge in triangle order, then read per corner and per triangle edge.
  int largest = -1;
  for (const auto& t : m_triangles)
    largest = std::max({largest, t[0], t[1], t[2]});
  std::vector<int> local(static_cast<std::size_t>(largest + 1), -1);
  std::map<std::pair<int, int>, int> edges;
  int vertices = 0;
  m_corner_vertex.resize(m_triangles.size());
  m_edge.resize(m_triangles.size());
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const auto& v = m_triangles[t];
    for (std::size_t k = 0; k < 3; ++k) {
      int& id = local[static_cast<std::size_t>(v[k])];
      if (id < 0) id = vertices++;
      m_corner_vertex[t][k] = id;
      const int next = static_cast<int>(edges.size());
      m_edge[t][k] = edges.try_emplace(std::minmax(v[k], v[(k + 1) % 3]), next).first->second;
    }
  }
  m_vertex_normals.assign(static_cast<std::size_t>(vertices), Eigen::Vector3d::Zero());
  m_edge_normals.assign(edges.size(), Eigen::Vector3d::Zero());
}

void SignedDistanceMesh::update(const Eigen::MatrixX3d& p) {
  const std::size_t n = m_triangles.size();
  m_corners.resize(n);
  m_face_normals.assign(n, Eigen::Vector3d::Zero());
  m_face_min.resize(n);
  m_face_max.resize(n);
  std::fill(m_vertex_normals.begin(), m_vertex_normals.end(), Eigen::Vector3d::Zero());
  std::fill(m_edge_normals.begin(), m_edge_normals.end(), Eigen::Vector3d::Zero());
  m_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  m_max = -m_min;
  for (std::size_t t = 0; t < n; ++t) {
    const auto& v = m_triangles[t];
    auto& x = m_corners[t];
    for (std::size_t k = 0; k < 3; ++k)
      x[k] = p.row(v[k]).transpose();
    const Eigen::Vector3d normal = (x[1] - x[0]).cross(x[2] - x[0]);
    const double length = normal.norm();
    const Eigen::Vector3d unit = length > 0.0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
    m_face_normals[t] = unit;
    m_face_min[t] = x[0].cwiseMin(x[1]).cwiseMin(x[2]);
    m_face_max[t] = x[0].cwiseMax(x[1]).cwiseMax(x[2]);
    m_min = m_min.cwiseMin(m_face_min[t]);
    m_max = m_max.cwiseMax(m_face_max[t]);
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
      // atan2 of |sin| and cos: accurate at every angle, unlike acos of the normalized dot product.
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      m_vertex_normals[static_cast<std::size_t>(m_corner_vertex[t][k])] += angle * unit;
      m_edge_normals[static_cast<std::size_t>(m_edge[t][k])] += unit;
    }
  }
  m_buckets.clear();
  m_cells.setZero();
}

void SignedDistanceMesh::build_search_grid() {
  const auto nf = static_cast<double>(m_triangles.size());
  // (An empty mesh gets one cell, which no search visits for long.)
  m_grid_min = m_triangles.empty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : m_min;
  const Eigen::Vector3d extent = m_triangles.empty() ? Eigen::Vector3d(Eigen::Vector3d::Ones())
                                                     : Eigen::Vector3d((m_max - m_min).cwiseMax(1e-9));
  // About as many cells as triangles: a surface crosses ~#F^(2/3) of them, ~#F^(1/3) triangles each.
  const double cell = std::max(std::cbrt(extent.prod() / std::max(1.0, nf)), 1e-6 * extent.maxCoeff());
  for (int a = 0; a < 3; ++a)
    m_cells[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / cell)));
  m_cell_size = extent.cwiseQuotient(m_cells.cast<double>());
  m_buckets.assign(static_cast<std::size_t>(m_cells.prod()), {});
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Eigen::Vector3i c0 = cell_of(m_face_min[t]), c1 = cell_of(m_face_max[t]);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x)
          m_buckets[voxel_index(m_cells, x, y, z)].push_back(static_cast<int>(t));
  }
}

Eigen::Vector3i SignedDistanceMesh::cell_of(const Eigen::Vector3d& x) const {
  Eigen::Vector3i cell;
  for (int a = 0; a < 3; ++a)
    cell[a] =
        std::clamp(static_cast<int>(std::floor((x[a] - m_grid_min[a]) / m_cell_size[a])), 0, m_cells[a] - 1);
  return cell;
}

MeshClosestPoint SignedDistanceMesh::closest(const Eigen::Vector3d& x) const {
  return m_buckets.empty() ? scan(x) : search_grid(x);
}

MeshClosestPoint SignedDistanceMesh::scan(const Eigen::Vector3d& x) const {
  MeshClosestPoint best;
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    if (box_distance_squared(x, m_face_min[t], m_face_max[t]) >= best.distance_squared) continue;
    const auto& v = m_corners[t];
    const TriangleClosestPoint c = closest_point_on_triangle(x, v[0], v[1], v[2]);
    const double d = (x - c.point).squaredNorm();
    if (d < best.distance_squared) best = {static_cast<int>(t), c, d};
  }
  return best;
}

MeshClosestPoint SignedDistanceMesh::search_grid(const Eigen::Vector3d& x) const {
  MeshClosestPoint best;
  const Eigen::Vector3i centre = cell_of(x);
  auto visit = [&](int cx, int cy, int cz) {
    if (cz < 0 || cy < 0 || cx < 0 || cz >= m_cells.z() || cy >= m_cells.y() || cx >= m_cells.x()) return;
    // A cell, or a triangle's box, no closer than the best so far cannot hold a closer point
    // (a tie keeps the first found either way, so the answer is the unpruned search's).
    const Eigen::Vector3d lo = m_grid_min + Eigen::Vector3d(cx, cy, cz).cwiseProduct(m_cell_size);
    if (box_distance_squared(x, lo, lo + m_cell_size) >= best.distance_squared) return;
    for (int t : m_buckets[voxel_index(m_cells, cx, cy, cz)]) {
      if (box_distance_squared(x, m_face_min[static_cast<std::size_t>(t)],
                               m_face_max[static_cast<std::size_t>(t)]) >= best.distance_squared)
        continue;
      const auto& v = m_corners[static_cast<std::size_t>(t)];
      const TriangleClosestPoint c = closest_point_on_triangle(x, v[0], v[1], v[2]);
      const double d = (c.point - x).squaredNorm();
      if (d < best.distance_squared) best = {t, c, d};
    }
  };
  // Growing shells of cells until the nearest candidate is closer than the shell.
  for (int ring = 0;; ++ring) {
    // Only the shell of cells at Chebyshev distance `ring`: O(ring^2) cells per ring.
    for (int dz = -ring; dz <= ring; ++dz) {
      for (int dy = -ring; dy <= ring; ++dy) {
        const bool whole_row = std::abs(dz) == ring || std::abs(dy) == ring;
        for (int dx = -ring; dx <= ring; dx += whole_row ? 1 : std::max(1, 2 * ring))
          visit(centre.x() + dx, centre.y() + dy, centre.z() + dz);
      }
    }
    // Cells within `ring` of the centre cover a ball of radius ring * (smallest cell edge) around x.
    const double covered = ring * m_cell_size.minCoeff();
    if (best.triangle >= 0 && best.distance_squared <= covered * covered) break;
    if (ring > m_cells.maxCoeff()) break;
  }
  return best;
}

Eigen::Vector3d SignedDistanceMesh::pseudonormal(const MeshClosestPoint& c) const {
  const auto t = static_cast<std::size_t>(c.triangle);
  const auto k = static_cast<std::size_t>(c.on_triangle.index);
  switch (c.on_triangle.feature) {
  case TriangleFeature::face: return m_face_normals[t];
  case TriangleFeature::edge: return m_edge_normals[static_cast<std::size_t>(m_edge[t][k])];
  case TriangleFeature::vertex: return m_vertex_normals[static_cast<std::size_t>(m_corner_vertex[t][k])];
  }
  return m_face_normals[t];
}

bool SignedDistanceMesh::inside(const Eigen::Vector3d& x, const MeshClosestPoint& c) const {
  return c.triangle >= 0 && (x - c.on_triangle.point).dot(pseudonormal(c)) < 0.0;
}

double SignedDistanceMesh::distance(const Eigen::Vector3d& x) const {
  return std::sqrt(closest(x).distance_squared);
}

double SignedDistanceMesh::signed_distance(const Eigen::Vector3d& x) const {
  const MeshClosestPoint c = closest(x);
  const double d = std::sqrt(c.distance_squared);
  return inside(x, c) ? -d : d;
}

} // namespace phantasm
