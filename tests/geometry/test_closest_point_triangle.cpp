// The closest point on a triangle against brute force over a dense sampling of the triangle, for
// points in every Voronoi region and for degenerate (collinear, zero-area) triangles.
#include "geometry/closest_point_triangle.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>

using namespace phantasm;

namespace {

/// The smallest distance from p to the points (i a + j b + k c) / n, i + j + k = n, and the
/// sample spacing bound: every point of the triangle is within longest edge / n of a sample.
std::pair<double, double> brute_force_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c, int n) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const int k = n - i - j;
      const Eigen::Vector3d q = (double(i) * a + double(j) * b + double(k) * c) / double(n);
      best = std::min(best, (q - p).norm());
    }
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  return {best, longest / n};
}

/// Checks one query: a point of the triangle that the barycentric weights reproduce, with the
/// feature they describe, no farther than any sample and within the sample spacing of the nearest.
void check_query(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                 const Eigen::Vector3d& c, const std::string& what, int samples = 300) {
  const TriangleClosestPoint r = closest_point_on_triangle(p, a, b, c);
  const double scale = std::max({1.0, a.norm(), b.norm(), c.norm(), p.norm()});
  ASSERT_TRUE(r.point.allFinite() && r.barycentric.allFinite()) << what;
  EXPECT_NEAR(r.barycentric.sum(), 1.0, 1e-12) << what;
  EXPECT_GE(r.barycentric.minCoeff(), -1e-12) << what;
  EXPECT_LE((r.barycentric[0] * a + r.barycentric[1] * b + r.barycentric[2] * c - r.point).norm(),
            1e-12 * scale)
      << what;
  switch (r.feature) {
  case TriangleFeature::vertex: EXPECT_EQ(r.barycentric[r.index], 1.0) << what; break;
  case TriangleFeature::edge: EXPECT_EQ(r.barycentric[(r.index + 2) % 3], 0.0) << what; break;
  case TriangleFeature::face: EXPECT_EQ(r.index, 0) << what; break;
  }
  const auto [brute, spacing] = brute_force_distance(p, a, b, c, samples);
  const double d = (r.point - p).norm();
  EXPECT_LE(d, brute + 1e-12 * scale) << what;
  EXPECT_GE(d, brute - spacing - 1e-12 * scale) << what;
}

} // namespace

TEST(ClosestPointTriangle, MatchesBruteForceInEveryVoronoiRegion) {
  const Eigen::Vector3d a(0.3, -0.2, 0.1), b(2.1, 0.4, -0.3), c(0.7, 1.9, 0.5);
  const std::array<Eigen::Vector3d, 3> corner = {a, b, c};
  const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
  std::set<std::pair<int, int>> seen; // (feature, index)
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0), height(-2.0, 2.0);
  auto query = [&](const Eigen::Vector3d& p, const std::string& what) {
    check_query(p, a, b, c, what);
    const TriangleClosestPoint r = closest_point_on_triangle(p, a, b, c);
    seen.insert({static_cast<int>(r.feature), r.index});
  };
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& v = corner[static_cast<std::size_t>(k)];
    const Eigen::Vector3d& next = corner[static_cast<std::size_t>((k + 1) % 3)];
    const Eigen::Vector3d& previous = corner[static_cast<std::size_t>((k + 2) % 3)];
    // Beyond the corner, opposite both of its edges.
    const Eigen::Vector3d out = -((next - v).normalized() + (previous - v).normalized()).normalized();
    // Beyond the middle of edge (k, k+1), away from the third corner, in the plane.
    const Eigen::Vector3d edge = (next - v).normalized();
    Eigen::Vector3d away = normal.cross(edge);
    if (away.dot(previous - v) > 0) away = -away;
    for (int i = 0; i < 20; ++i) {
      query(v + (0.1 + unit(random)) * out + height(random) * normal, "corner " + std::to_string(k));
      query(v + (0.2 + 0.6 * unit(random)) * (next - v) + (0.05 + unit(random)) * away +
                height(random) * normal,
            "edge " + std::to_string(k));
    }
  }
  for (int i = 0; i < 20; ++i) {
    double u = unit(random), v = unit(random);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    query(a + u * (b - a) + v * (c - a) + height(random) * normal, "interior");
  }
  std::uniform_real_distribution<double> box(-3.0, 4.0);
  for (int i = 0; i < 200; ++i)
    query({box(random), box(random), box(random)}, "random point " + std::to_string(i));
  // Every corner, every edge and the interior answered at least once.
  EXPECT_EQ(seen.size(), 7u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(seen.count({static_cast<int>(TriangleFeature::vertex), k})) << "corner " << k;
    EXPECT_TRUE(seen.count({static_cast<int>(TriangleFeature::edge), k})) << "edge " << k;
  }
  EXPECT_TRUE(seen.count({static_cast<int>(TriangleFeature::face), 0}));
}

TEST(ClosestPointTriangle, CornersEdgesAndInteriorPointsAreTheirOwnClosestPoints) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(closest_point_on_triangle(a, a, b, c).feature, TriangleFeature::vertex);
  EXPECT_EQ(closest_point_on_triangle(b, a, b, c).index, 1);
  const TriangleClosestPoint mid = closest_point_on_triangle(Eigen::Vector3d(0.5, 0.5, 0), a, b, c);
  EXPECT_EQ(mid.feature, TriangleFeature::edge);
  EXPECT_EQ(mid.index, 1);
  EXPECT_LE((mid.point - Eigen::Vector3d(0.5, 0.5, 0)).norm(), 1e-15);
  const TriangleClosestPoint inside = closest_point_on_triangle(Eigen::Vector3d(0.2, 0.3, 0.7), a, b, c);
  EXPECT_EQ(inside.feature, TriangleFeature::face);
  EXPECT_LE((inside.barycentric - Eigen::Vector3d(0.5, 0.2, 0.3)).norm(), 1e-15);
}

TEST(ClosestPointTriangle, DegenerateTrianglesMatchBruteForce) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> box(-1.5, 2.5);
  for (double offset : {-1e-12, 0.0, 1e-12}) {
    const std::string size = " (offset " + std::to_string(offset) + ")";
    // Collinear: the third corner between the others, beyond them, and two corners coincident.
    const std::array<std::array<Eigen::Vector3d, 3>, 6> triangles = {{
        {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.4, offset, 0)},
        {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1.7, offset, offset)},
        {Eigen::Vector3d(0.4, offset, 0), Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)},
        {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(offset, 0, 0), Eigen::Vector3d(1, 1, 0)},
        // Zero area: all corners within |offset| of one point.
        {Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(0.5 + offset, 0.5, 0.5),
         Eigen::Vector3d(0.5, 0.5 + offset, 0.5 - offset)},
        {Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(0.5, 0.5, 0.5),
         Eigen::Vector3d(0.5, 0.5, 0.5 + offset)},
    }};
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const auto& [a, b, c] = triangles[t];
      for (int i = 0; i < 200; ++i) {
        const Eigen::Vector3d p = i < 100
                                      ? Eigen::Vector3d(box(random), box(random), box(random))
                                      // near the line of the collinear ones
                                      : Eigen::Vector3d(box(random), 1e-3 * box(random), 1e-3 * box(random));
        check_query(p, a, b, c, "triangle " + std::to_string(t) + size + " point " + std::to_string(i), 200);
      }
    }
  }
}
