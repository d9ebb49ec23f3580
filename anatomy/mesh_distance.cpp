#include "anatomy/mesh_distance.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace phantasm {
namespace {

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5),
/// with the feature it lies on.
std::pair<Eigen::Vector3d, int> closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, 1};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, 2};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return {a + d1 / (d1 - d3) * ab, 4};
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, 3};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return {a + d2 / (d2 - d6) * ac, 6};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return {b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b), 5};
  const double denominator = 1.0 / (va + vb + vc);
  return {a + ab * (vb * denominator) + ac * (vc * denominator), 0};
}

} // namespace

MeshDistance::MeshDistance(const TriangleMesh& mesh) : m_mesh(mesh) {
  const Eigen::Index nf = mesh.face_count();
  m_min = mesh.vertices.colwise().minCoeff().transpose();
  const Eigen::Vector3d max = mesh.vertices.colwise().maxCoeff().transpose();
  const Eigen::Vector3d extent = (max - m_min).cwiseMax(1e-9);
  // About as many cells as triangles: a surface crosses ~#F^(2/3) of them, ~#F^(1/3) triangles each.
  const double cell =
      std::max(std::cbrt(extent.prod() / std::max<double>(1.0, double(nf))), 1e-6 * extent.maxCoeff());
  for (int a = 0; a < 3; ++a)
    m_cells[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / cell)));
  m_cell_size = extent.cwiseQuotient(m_cells.cast<double>());
  m_buckets.assign(static_cast<std::size_t>(m_cells.prod()), {});
  m_face_normals.resize(nf, 3);
  m_vertex_normals = Eigen::MatrixX3d::Zero(mesh.vertex_count(), 3);
  std::map<std::pair<int, int>, Eigen::Vector3d> edge_sum;
  for (Eigen::Index t = 0; t < nf; ++t) {
    Eigen::Vector3d corner[3];
    for (int k = 0; k < 3; ++k)
      corner[k] = mesh.vertex(mesh.faces(t, k));
    const Eigen::Vector3d n = (corner[1] - corner[0]).cross(corner[2] - corner[0]).normalized();
    m_face_normals.row(t) = n.transpose();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 = (corner[(k + 1) % 3] - corner[k]).normalized();
      const Eigen::Vector3d e2 = (corner[(k + 2) % 3] - corner[k]).normalized();
      m_vertex_normals.row(mesh.faces(t, k)) += std::acos(std::clamp(e1.dot(e2), -1.0, 1.0)) * n.transpose();
      // try_emplace with an explicit zero: Eigen vectors are not zero-initialized by default.
      edge_sum.try_emplace(std::minmax(mesh.faces(t, k), mesh.faces(t, (k + 1) % 3)), Eigen::Vector3d::Zero())
          .first->second += n;
    }
    const Eigen::Vector3d lo = corner[0].cwiseMin(corner[1]).cwiseMin(corner[2]);
    const Eigen::Vector3d hi = corner[0].cwiseMax(corner[1]).cwiseMax(corner[2]);
    const Eigen::Vector3i c0 = cell_of(lo), c1 = cell_of(hi);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x)
          m_buckets[static_cast<std::size_t>((z * m_cells.y() + y) * m_cells.x() + x)].push_back(t);
  }
  m_edge_normals.resize(static_cast<std::size_t>(nf));
  for (Eigen::Index t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) {
      m_edge_normals[static_cast<std::size_t>(t)][static_cast<std::size_t>(k)] =
          edge_sum.at(std::minmax(mesh.faces(t, k), mesh.faces(t, (k + 1) % 3)));
    }
  }
}

Eigen::Vector3i MeshDistance::cell_of(const Eigen::Vector3d& x) const {
  Eigen::Vector3i cell;
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(static_cast<int>(std::floor((x[a] - m_min[a]) / m_cell_size[a])), 0, m_cells[a] - 1);
  }
  return cell;
}

const std::vector<Eigen::Index>& MeshDistance::bucket(const Eigen::Vector3i& c) const {
  return m_buckets[static_cast<std::size_t>((c.z() * m_cells.y() + c.y()) * m_cells.x() + c.x())];
}

MeshDistance::Closest MeshDistance::closest(const Eigen::Vector3d& x) const {
  Closest best{std::numeric_limits<double>::infinity(), x, -1, 0};
  const Eigen::Vector3i centre = cell_of(x);
  // Search growing shells of cells until the nearest candidate is closer than the shell.
  auto visit = [&](int cx, int cy, int cz) {
    if (cz < 0 || cy < 0 || cx < 0 || cz >= m_cells.z() || cy >= m_cells.y() || cx >= m_cells.x()) return;
    for (Eigen::Index t : bucket({cx, cy, cz})) {
      const auto [point, feature] =
          closest_on_triangle(x, m_mesh.vertex(m_mesh.faces(t, 0)), m_mesh.vertex(m_mesh.faces(t, 1)),
                              m_mesh.vertex(m_mesh.faces(t, 2)));
      const double d2 = (point - x).squaredNorm();
      if (d2 < best.distance_squared) best = {d2, point, t, feature};
    }
  };
  for (int ring = 0;; ++ring) {
    // Only the shell of cells at Chebyshev distance `ring`: O(ring^2) cells per ring.
    for (int dz = -ring; dz <= ring; ++dz) {
      for (int dy = -ring; dy <= ring; ++dy) {
        const bool whole_row = std::abs(dz) == ring || std::abs(dy) == ring;
        for (int dx = -ring; dx <= ring; dx += whole_row ? 1 : std::max(1, 2 * ring)) {
          visit(centre.x() + dx, centre.y() + dy, centre.z() + dz);
        }
      }
    }
    // Cells within `ring` of the centre cover a ball of radius ring * (smallest cell edge) around x.
    const double covered = ring * m_cell_size.minCoeff();
    if (best.triangle >= 0 && best.distance_squared <= covered * covered) break;
    if (ring > m_cells.maxCoeff()) break;
  }
  return best;
}

double MeshDistance::distance(const Eigen::Vector3d& x) const {
  return std::sqrt(closest(x).distance_squared);
}

double MeshDistance::signed_distance(const Eigen::Vector3d& x) const {
  const Closest c = closest(x);
  Eigen::Vector3d normal;
  if (c.feature == 0) {
    normal = m_face_normals.row(c.triangle).transpose();
  } else if (c.feature <= 3) {
    normal = m_vertex_normals.row(m_mesh.faces(c.triangle, c.feature - 1)).transpose();
  } else {
    // Features 4, 5, 6 are edges ab, bc, ca: edge k = feature - 4 joins corners k and k + 1.
    normal = m_edge_normals[static_cast<std::size_t>(c.triangle)][static_cast<std::size_t>(c.feature - 4)];
  }
  const double d = std::sqrt(c.distance_squared);
  return normal.dot(x - c.point) < 0.0 ? -d : d;
}

SurfaceDistance symmetric_distance(const TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& samples_on_b,
                                   const std::vector<double>& mesh_vertex_distances_to_b) {
  SurfaceDistance result;
  const MeshDistance to_mesh(mesh);
  double total = 0.0;
  for (const auto& p : samples_on_b) {
    const double d = to_mesh.distance(p);
    result.hausdorff_mm = std::max(result.hausdorff_mm, d);
    total += d;
  }
  for (double d : mesh_vertex_distances_to_b) {
    result.hausdorff_mm = std::max(result.hausdorff_mm, std::abs(d));
    total += std::abs(d);
  }
  result.mean_mm = total / static_cast<double>(samples_on_b.size() + mesh_vertex_distances_to_b.size());
  return result;
}

} // namespace phantasm
