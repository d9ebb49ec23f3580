// The closest point of a triangle to a point (Ericson's Voronoi region test); see
// closest_point_triangle.hpp.
#include "geometry/closest_point_triangle.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>

namespace phantasm {
namespace {

/// sin^2 of the angle at a below which a triangle counts as flat: 1e-20, an angle of 1e-10 rad.
/// The regions' arithmetic stays accurate to ~1e-12 of the edge lengths down to angles of 1e-11
/// and fails near 1e-12, where the corners' rounding is as large as the triangle's width.
constexpr double k_flat = 1e-20;

/// The closest point of the three edges taken as segments: the answer for a triangle without
/// area (collinear or coincident corners), where the regions of the general case divide by zero.
TriangleClosestPoint closest_on_edges(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d* corner[3] = {&a, &b, &c};
  TriangleClosestPoint best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const int next = (k + 1) % 3;
    const Eigen::Vector3d& from = *corner[k];
    const Eigen::Vector3d& to = *corner[next];
    const Eigen::Vector3d edge = to - from;
    const double length_squared = edge.squaredNorm();
    const double t = length_squared > 0.0 ? std::clamp((p - from).dot(edge) / length_squared, 0.0, 1.0) : 0.0;
    TriangleClosestPoint r;
    r.point = t == 0.0 ? from : t == 1.0 ? to : Eigen::Vector3d(from + t * edge);
    r.barycentric[k] = 1.0 - t;
    r.barycentric[next] = t;
    r.feature = t == 0.0 || t == 1.0 ? TriangleFeature::vertex : TriangleFeature::edge;
    r.index = t == 1.0 ? next : k;
    const double d = (p - r.point).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best = r;
    }
  }
  return best;
}

} // namespace

TriangleClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, {1, 0, 0}, TriangleFeature::vertex, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, {0, 1, 0}, TriangleFeature::vertex, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    if (d1 - d3 <= 0.0) return closest_on_edges(p, a, b, c); // a == b
    const double v = d1 / (d1 - d3);
    return {a + v * ab, {1 - v, v, 0}, TriangleFeature::edge, 0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, {0, 0, 1}, TriangleFeature::vertex, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    if (d2 - d6 <= 0.0) return closest_on_edges(p, a, b, c); // a == c
    const double w = d2 / (d2 - d6);
    return {a + w * ac, {1 - w, 0, w}, TriangleFeature::edge, 2};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    if ((d4 - d3) + (d5 - d6) <= 0.0) return closest_on_edges(p, a, b, c); // b == c
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), {0, 1 - w, w}, TriangleFeature::edge, 1};
  }
  // va + vb + vc = |ab x ac|^2, from differences that cancel as the triangle flattens: a flat
  // triangle is its edges.
  if (ab.cross(ac).squaredNorm() <= k_flat * ab.squaredNorm() * ac.squaredNorm())
    return closest_on_edges(p, a, b, c);
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return {a + ab * v + ac * w, {1 - v - w, v, w}, TriangleFeature::face, 0};
}

} // namespace phantasm
