// Tet geometry: barycentric coordinates, point location in a tet mesh against brute force, and
// the outward boundary faces of a subdivided cube (count, divergence theorem, enclosed volume).
#include "geometry/tet_boundary.hpp"
#include "geometry/tet_location.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <optional>
#include <random>
#include <vector>

using namespace phantasm;

namespace {

struct TetMeshData {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX4i tets;
};

/// The cube [0, size]^3 cut into n^3 cells of 6 tets each (the Kuhn split along the main
/// diagonal: conforming across cells), interior vertices jittered by up to `jitter` of a cell,
/// every other tet listed with two corners swapped (either orientation).
TetMeshData subdivided_cube(int n, double size, double jitter, unsigned seed) {
  TetMeshData m;
  const int side = n + 1;
  m.vertices.resize(side * side * side, 3);
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> shake(-jitter, jitter);
  auto id = [&](int i, int j, int k) { return (k * side + j) * side + i; };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        Eigen::Vector3d x(i, j, k);
        for (int a = 0; a < 3; ++a)
          if (x[a] > 0 && x[a] < n) x[a] += shake(random);
        m.vertices.row(id(i, j, k)) = (size / n) * x.transpose();
      }
  // The six monotone paths from corner (0,0,0) to (1,1,1) of a cell.
  const std::array<std::array<int, 3>, 6> orders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  m.tets.resize(6 * n * n * n, 4);
  int t = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& order : orders) {
          int c[3] = {i, j, k};
          Eigen::Vector4i tet;
          tet[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[order[static_cast<std::size_t>(s)]];
            tet[s + 1] = id(c[0], c[1], c[2]);
          }
          if (t % 2) std::swap(tet[2], tet[3]);
          m.tets.row(t++) = tet.transpose();
        }
  return m;
}

Eigen::Vector3d corner(const TetMeshData& m, Eigen::Index t, int k) {
  return m.vertices.row(m.tets(t, k)).transpose();
}

} // namespace

TEST(TetLocation, BarycentricCoordinatesSumToOneAndReproduceThePoint) {
  std::mt19937 random(1);
  std::uniform_real_distribution<double> box(-5.0, 5.0);
  auto point = [&] { return Eigen::Vector3d(box(random), box(random), box(random)); };
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a = point(), b = point(), c = point(), d = point();
    if (std::abs((b - a).dot((c - a).cross(d - a))) < 1.0) continue; // not nearly flat
    const Eigen::Vector3d x = point();
    const Eigen::Vector4d w = tet_barycentric(x, a, b, c, d);
    EXPECT_NEAR(w.sum(), 1.0, 1e-12);
    EXPECT_LE((w[0] * a + w[1] * b + w[2] * c + w[3] * d - x).norm(), 1e-10);
    // A convex combination with positive weights lies inside: its weights come back.
    Eigen::Vector4d inside(box(random), box(random), box(random), box(random));
    inside = inside.cwiseAbs() / inside.cwiseAbs().sum();
    const Eigen::Vector3d y = inside[0] * a + inside[1] * b + inside[2] * c + inside[3] * d;
    EXPECT_LE((tet_barycentric(y, a, b, c, d) - inside).norm(), 1e-10);
  }
}

TEST(TetLocation, FindsTheSameTetAsBruteForce) {
  const TetMeshData m = subdivided_cube(4, 8.0, 0.1, 2);
  const TetMeshLocator locator(m.vertices, m.tets);
  ASSERT_EQ(locator.tet_count(), m.tets.rows());
  std::mt19937 random(4);
  std::uniform_real_distribution<double> box(-1.0, 9.0);
  int found = 0, missed = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d x(box(random), box(random), box(random));
    // Brute force: the first tet whose weights are all >= 0, and the tet whose smallest weight is largest.
    Eigen::Index first = -1, least_outside = -1;
    double best = -1e300;
    for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
      const Eigen::Vector4d w =
          tet_barycentric(x, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), corner(m, t, 3));
      EXPECT_LE((w - locator.barycentric(t, x)).norm(), 1e-9);
      if (first < 0 && w.minCoeff() >= -1e-12) first = t;
      if (w.minCoeff() > best) best = w.minCoeff(), least_outside = t;
    }
    const std::optional<TetLocation> location = locator.find(x);
    ASSERT_EQ(location.has_value(), first >= 0) << x.transpose();
    const TetLocation nearest = locator.nearest(x);
    if (location) {
      ++found;
      EXPECT_EQ(location->tet, first);
      EXPECT_GE(location->weights.minCoeff(), -1e-12);
      EXPECT_EQ(nearest.tet, first); // the first holding tet as well
    } else {
      ++missed;
      EXPECT_EQ(nearest.tet, least_outside);
      EXPECT_LT(nearest.weights.minCoeff(), 0.0);
    }
  }
  EXPECT_GT(found, 500);
  EXPECT_GT(missed, 500);
}

// The locator's grid lists every tet a point may lie in: at the mesh's vertices, edge midpoints
// and face centroids (held by several tets at once, and on the faces of the grid's cells), and in
// a mesh of two cubes far apart (a box the tets fill little of), and at points outside near and
// far, nearest and find return what trying every tet in list order returns: the first holding
// tet, or the first of those least outside.
TEST(TetLocation, TheGridGivesWhatEveryTetInListOrderGivesAtSharedCornersAndFaces) {
  TetMeshData m = subdivided_cube(5, 10.0, 0.15, 7);
  const TetMeshData far = subdivided_cube(2, 3.0, 0.1, 8);
  const Eigen::Index nv = m.vertices.rows(), nt = m.tets.rows();
  m.vertices.conservativeResize(nv + far.vertices.rows(), 3);
  m.vertices.bottomRows(far.vertices.rows()) = far.vertices.rowwise() + Eigen::RowVector3d(60.0, -40.0, 25.0);
  m.tets.conservativeResize(nt + far.tets.rows(), 4);
  m.tets.bottomRows(far.tets.rows()) = far.tets.array() + static_cast<int>(nv);
  const TetMeshLocator locator(m.vertices, m.tets);
  std::vector<Eigen::Vector3d> points;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
    points.push_back(m.vertices.row(v).transpose());
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        points.push_back(0.5 * (corner(m, t, a) + corner(m, t, b)));
        points.push_back(
            (corner(m, t, 0) + corner(m, t, 1) + corner(m, t, 2) + corner(m, t, 3) - corner(m, t, a)) / 3.0);
      }
  points.push_back(Eigen::Vector3d(30.0, -20.0, 12.0));   // between the cubes
  points.push_back(Eigen::Vector3d(-0.5, 5.0, 5.0));      // just outside
  points.push_back(Eigen::Vector3d(400.0, -300.0, 90.0)); // far outside the grid
  std::mt19937 random(11);
  std::uniform_real_distribution<double> around(-15.0, 75.0);
  for (int i = 0; i < 300; ++i) // mostly outside, at every distance
    points.push_back(Eigen::Vector3d(around(random), around(random) - 40.0, around(random)));
  int held = 0, shared = 0;
  for (const Eigen::Vector3d& x : points) {
    Eigen::Index first = -1, first_found = -1, least_outside = -1, holders = 0;
    double best = -std::numeric_limits<double>::infinity();
    for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
      const Eigen::Vector4d w = locator.barycentric(t, x);
      const bool in_box = (x.array() >= locator.tet_low(t).array() - 1e-9).all() &&
                          (x.array() <= locator.tet_high(t).array() + 1e-9).all();
      if (w.minCoeff() >= 0.0) ++holders;
      if (first < 0 && w.minCoeff() >= 0.0) first = t;
      if (first_found < 0 && in_box && w.minCoeff() >= -1e-12) first_found = t;
      if (w.minCoeff() > best) best = w.minCoeff(), least_outside = t;
    }
    held += first >= 0;
    shared += holders > 1;
    EXPECT_EQ(locator.nearest(x).tet, first >= 0 ? first : least_outside) << x.transpose();
    const std::optional<TetLocation> found = locator.find(x);
    EXPECT_EQ(found ? found->tet : -1, first_found) << x.transpose();
  }
  EXPECT_GT(held, 1000);
  EXPECT_GT(shared, 1000) << "points held by several tets, where list order decides";
}

TEST(TetBoundary, SubdividedCubeHasItsSurfaceOrientedOutward) {
  for (int n : {1, 2, 5}) {
    const double size = 3.0;
    const TetMeshData m = subdivided_cube(n, size, 0.1, 9);
    const Eigen::MatrixX3i faces = tet_boundary_faces(m.vertices, m.tets);
    // Two triangles per square of each cube face.
    ASSERT_EQ(faces.rows(), 12 * n * n);
    Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
    double volume = 0.0, area = 0.0;
    const Eigen::Vector3d centre = Eigen::Vector3d::Constant(size / 2);
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      const Eigen::Vector3d a = m.vertices.row(faces(f, 0)).transpose(),
                            b = m.vertices.row(faces(f, 1)).transpose(),
                            c = m.vertices.row(faces(f, 2)).transpose();
      const Eigen::Vector3d twice_area_normal = (b - a).cross(c - a);
      normal_sum += twice_area_normal / 2;
      area += twice_area_normal.norm() / 2;
      // Divergence theorem with div x = 3: V = 1/3 sum (centroid . n) area = 1/6 sum a . (b x c).
      volume += a.dot(b.cross(c)) / 6.0;
      // Each face of the cube surface points away from the centre.
      EXPECT_GT(twice_area_normal.dot((a + b + c) / 3 - centre), 0.0);
    }
    EXPECT_LE(normal_sum.norm(), 1e-12 * area);
    EXPECT_NEAR(area, 6 * size * size, 1e-12 * area);
    EXPECT_NEAR(volume, size * size * size, 1e-12);
  }
}
