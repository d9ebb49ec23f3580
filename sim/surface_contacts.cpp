#include "sim/surface_contacts.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace phantasm {
namespace {

/// Which feature of a triangle a closest point lies on.
enum class Feature { face, edge, vertex };

struct TrianglePoint {
  Eigen::Vector3d point;
  Eigen::Vector3d barycentric; ///< of the point, over (a, b, c)
  Feature feature = Feature::face;
  int index = 0; ///< the edge (k: corners k, k+1) or the corner
};

/// The closest point of triangle (a, b, c) to x, with its feature (Ericson, Real-Time Collision
/// Detection, 5.1.5).
TrianglePoint closest_on_triangle(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, {1, 0, 0}, Feature::vertex, 0};
  const Eigen::Vector3d bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, {0, 1, 0}, Feature::vertex, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {a + v * ab, {1 - v, v, 0}, Feature::edge, 0};
  }
  const Eigen::Vector3d cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, {0, 0, 1}, Feature::vertex, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {a + w * ac, {1 - w, 0, w}, Feature::edge, 2};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), {0, 1 - w, w}, Feature::edge, 1};
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return {a + ab * v + ac * w, {1 - v - w, v, w}, Feature::face, 0};
}

double box_distance_squared(const Eigen::Vector3d& x, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).squaredNorm();
}

} // namespace

std::vector<std::vector<int>> opposing_surfaces(const std::vector<ContactSurface>& surfaces,
                                                const std::vector<std::array<int, 2>>& pairs,
                                                Eigen::Index vertex_count) {
  std::vector<std::vector<int>> opposing(static_cast<std::size_t>(vertex_count));
  for (const auto& [a, b] : pairs) {
    for (const auto& [own, other] : {std::pair{a, b}, std::pair{b, a}}) {
      for (int v : surfaces[static_cast<std::size_t>(own)].vertices) {
        auto& list = opposing[static_cast<std::size_t>(v)];
        if (std::find(list.begin(), list.end(), other) == list.end()) list.push_back(other);
      }
    }
  }
  return opposing;
}

ContactGeometry::ContactGeometry(const std::vector<ContactSurface>& surfaces)
    : m_surfaces(surfaces), m_local(surfaces.size()), m_cache(surfaces.size()) {
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    int largest = -1;
    for (const auto& t : surfaces[s].triangles)
      largest = std::max({largest, t[0], t[1], t[2]});
    m_local[s].assign(static_cast<std::size_t>(largest + 1), -1);
    int next = 0;
    for (const auto& t : surfaces[s].triangles)
      for (int v : t)
        if (m_local[s][static_cast<std::size_t>(v)] < 0) m_local[s][static_cast<std::size_t>(v)] = next++;
    m_cache[s].vertex_normals.assign(static_cast<std::size_t>(next), Eigen::Vector3d::Zero());
  }
}

void ContactGeometry::update(const Eigen::MatrixX3d& p) {
  m_positions = p;
  for (std::size_t s = 0; s < m_surfaces.size(); ++s) {
    const auto& triangles = m_surfaces[s].triangles;
    Cache& cache = m_cache[s];
    const std::size_t n = triangles.size();
    cache.face_normals.assign(n, Eigen::Vector3d::Zero());
    cache.face_min.resize(n);
    cache.face_max.resize(n);
    std::fill(cache.vertex_normals.begin(), cache.vertex_normals.end(), Eigen::Vector3d::Zero());
    cache.min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    cache.max = -cache.min;
    std::map<std::pair<int, int>, Eigen::Vector3d> edge_sums;
    for (std::size_t t = 0; t < n; ++t) {
      const auto& v = triangles[t];
      const Eigen::Vector3d x[3] = {p.row(v[0]).transpose(), p.row(v[1]).transpose(),
                                    p.row(v[2]).transpose()};
      const Eigen::Vector3d normal = (x[1] - x[0]).cross(x[2] - x[0]);
      const double length = normal.norm();
      const Eigen::Vector3d unit = length > 0.0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
      cache.face_normals[t] = unit;
      cache.face_min[t] = x[0].cwiseMin(x[1]).cwiseMin(x[2]);
      cache.face_max[t] = x[0].cwiseMax(x[1]).cwiseMax(x[2]);
      cache.min = cache.min.cwiseMin(cache.face_min[t]);
      cache.max = cache.max.cwiseMax(cache.face_max[t]);
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
        const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        cache.vertex_normals[static_cast<std::size_t>(m_local[s][static_cast<std::size_t>(v[k])])] +=
            angle * unit;
        const int a = v[static_cast<std::size_t>(k)], b = v[static_cast<std::size_t>((k + 1) % 3)];
        // (Eigen's vectors start uninitialized: insert a zero first.)
        edge_sums.try_emplace({std::min(a, b), std::max(a, b)}, Eigen::Vector3d::Zero()).first->second +=
            unit;
      }
    }
    cache.edge_normals.resize(n);
    for (std::size_t t = 0; t < n; ++t) {
      const auto& v = triangles[t];
      for (int k = 0; k < 3; ++k) {
        const int a = v[static_cast<std::size_t>(k)], b = v[static_cast<std::size_t>((k + 1) % 3)];
        cache.edge_normals[t][static_cast<std::size_t>(k)] = edge_sums[{std::min(a, b), std::max(a, b)}];
      }
    }
  }
}

SurfaceQuery ContactGeometry::query(int s, const Eigen::Vector3d& x) const {
  SurfaceQuery q;
  const Cache& cache = m_cache[static_cast<std::size_t>(s)];
  if ((x.array() < cache.min.array()).any() || (x.array() > cache.max.array()).any()) return q;
  const auto& triangles = m_surfaces[static_cast<std::size_t>(s)].triangles;
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_face = 0;
  TrianglePoint best_point;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (box_distance_squared(x, cache.face_min[t], cache.face_max[t]) >= best) continue;
    const auto& v = triangles[t];
    const TrianglePoint c =
        closest_on_triangle(x, m_positions.row(v[0]).transpose(), m_positions.row(v[1]).transpose(),
                            m_positions.row(v[2]).transpose());
    const double d = (x - c.point).squaredNorm();
    if (d < best) {
      best = d;
      best_face = t;
      best_point = c;
    }
  }
  if (!std::isfinite(best)) return q;
  Eigen::Vector3d pseudonormal = cache.face_normals[best_face];
  if (best_point.feature == Feature::edge) {
    pseudonormal = cache.edge_normals[best_face][static_cast<std::size_t>(best_point.index)];
  } else if (best_point.feature == Feature::vertex) {
    const int v = triangles[best_face][static_cast<std::size_t>(best_point.index)];
    pseudonormal = cache.vertex_normals[static_cast<std::size_t>(
        m_local[static_cast<std::size_t>(s)][static_cast<std::size_t>(v)])];
  }
  const Eigen::Vector3d offset = x - best_point.point;
  q.closest = best_point.point;
  q.triangle = triangles[best_face];
  q.barycentric = best_point.barycentric;
  q.distance = std::sqrt(best);
  q.inside = offset.dot(pseudonormal) < 0.0;
  // The contact plane's normal: along the offset where there is one, else the pseudonormal.
  if (q.distance > 1e-12 * (cache.max - cache.min).norm())
    q.normal = (q.inside ? -offset : offset) / q.distance;
  else
    q.normal = pseudonormal.normalized();
  return q;
}

} // namespace phantasm
