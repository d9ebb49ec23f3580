// Signed distance to a closed triangle mesh: a sphere mesh against the analytic distance to the
// sphere within the chord sagitta, its sign, and the unit gradient away from the medial axis.
#include "geometry/mesh_signed_distance.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

using namespace phantasm;

namespace {

struct Mesh {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX3i faces;
};

/// An icosahedron subdivided `levels` times, vertices on the sphere of radius r about the origin,
/// faces counter-clockwise seen from outside.
Mesh icosphere(int levels, double r) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : v)
    x.normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto found = middle.find(key);
      if (found != middle.end()) return found->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      return middle[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& [a, b, c] : f) {
      const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      finer.insert(finer.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    f = std::move(finer);
  }
  Mesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    m.vertices.row(static_cast<Eigen::Index>(i)) = r * v[i].transpose();
  m.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i)
    m.faces.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  return m;
}

/// The largest gap between the sphere and the flat faces: R - sqrt(R^2 - rho^2), rho the largest
/// circumradius of a face.
double sagitta(const Mesh& m, double r) {
  double rho = 0.0;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    const Eigen::Vector3d a = m.vertices.row(m.faces(f, 0)).transpose(),
                          b = m.vertices.row(m.faces(f, 1)).transpose(),
                          c = m.vertices.row(m.faces(f, 2)).transpose();
    const double area2 = (b - a).cross(c - a).norm();
    rho = std::max(rho, (b - a).norm() * (c - b).norm() * (a - c).norm() / (2.0 * area2));
  }
  return r - std::sqrt(r * r - rho * rho);
}

Eigen::Vector3d random_direction(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Vector3d(normal(random), normal(random), normal(random)).normalized();
}

/// The mesh for distance queries, searched through its tree or by scanning every triangle.
SignedDistanceMesh distance_mesh(const Mesh& m, bool with_tree) {
  SignedDistanceMesh mesh(m.faces);
  mesh.update(m.vertices);
  if (with_tree) mesh.build_search_tree();
  return mesh;
}

} // namespace

TEST(MeshSignedDistance, SphereMeshMatchesTheSphereWithinTheSagittaWithTheRightSign) {
  const double r = 20.0;
  const Mesh sphere = icosphere(3, r);
  const double s = sagitta(sphere, r);
  ASSERT_GT(s, 0.0);
  ASSERT_LT(s, 0.02 * r);
  const SignedDistanceMesh scanned = distance_mesh(sphere, false), tree = distance_mesh(sphere, true);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> radius(0.0, 2.5 * r);
  int inside = 0, outside = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d x = radius(random) * random_direction(random);
    const double exact = x.norm() - r;
    for (const SignedDistanceMesh* mesh : {&scanned, &tree}) {
      const double d = mesh->signed_distance(x);
      EXPECT_NEAR(d, exact, s * (1 + 1e-9)) << x.transpose();
      EXPECT_NEAR(std::abs(d), mesh->distance(x), 1e-12);
      if (std::abs(exact) > s) {
        EXPECT_EQ(d < 0.0, exact < 0.0) << x.transpose();
        EXPECT_EQ(mesh->inside(x, mesh->closest(x)), exact < 0.0);
      }
    }
    // The two searches find the same point of the same triangle.
    EXPECT_EQ(scanned.closest(x).triangle, tree.closest(x).triangle) << x.transpose();
    EXPECT_EQ(scanned.closest(x).distance_squared, tree.closest(x).distance_squared);
    (exact < 0 ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 100);
}

TEST(MeshSignedDistance, SignIsRightAtVerticesEdgesAndFacesJustOffTheSurface) {
  // Points a small step along the outward direction from vertices, edge midpoints and face
  // centroids: closest features of every kind, where only the pseudonormals decide the sign.
  const Mesh sphere = icosphere(2, 5.0);
  SignedDistanceMesh mesh(sphere.faces);
  mesh.update(sphere.vertices);
  int features[3] = {0, 0, 0};
  for (Eigen::Index f = 0; f < sphere.faces.rows(); ++f) {
    const Eigen::Vector3d a = sphere.vertices.row(sphere.faces(f, 0)).transpose(),
                          b = sphere.vertices.row(sphere.faces(f, 1)).transpose(),
                          c = sphere.vertices.row(sphere.faces(f, 2)).transpose();
    for (const Eigen::Vector3d& p : {a, Eigen::Vector3d((a + b) / 2), Eigen::Vector3d((a + b + c) / 3)}) {
      for (double step : {-1e-6, 1e-6}) {
        const Eigen::Vector3d x = p + step * p.normalized();
        const MeshClosestPoint closest = mesh.closest(x);
        ++features[static_cast<int>(closest.on_triangle.feature)];
        EXPECT_EQ(mesh.signed_distance(x) < 0.0, step < 0.0) << x.transpose();
        EXPECT_NEAR(std::abs(mesh.signed_distance(x)), 1e-6, 1e-7);
      }
    }
  }
  EXPECT_GT(features[static_cast<int>(TriangleFeature::face)], 0);
  EXPECT_GT(features[static_cast<int>(TriangleFeature::edge)], 0);
  EXPECT_GT(features[static_cast<int>(TriangleFeature::vertex)], 0);
}

TEST(MeshSignedDistance, GradientHasUnitLengthAwayFromTheMedialAxis) {
  const double r = 10.0;
  const Mesh sphere = icosphere(2, r);
  SignedDistanceMesh mesh(sphere.faces);
  mesh.update(sphere.vertices);
  mesh.build_search_tree();
  const double h = 1e-5;
  auto gradient = [&](const Eigen::Vector3d& x) {
    Eigen::Vector3d g;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(a);
      g[a] = (mesh.signed_distance(x + e) - mesh.signed_distance(x - e)) / (2 * h);
    }
    return g;
  };
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Outside a convex mesh the distance is smooth everywhere.
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d x = (r * (1.05 + unit(random))) * random_direction(random);
    EXPECT_NEAR(gradient(x).norm(), 1.0, 1e-6) << x.transpose();
  }
  // Inside, the medial axis reaches up to every edge: stay below face centres, shallower than a
  // tenth of the face's inradius.
  for (Eigen::Index f = 0; f < sphere.faces.rows(); f += 7) {
    const Eigen::Vector3d a = sphere.vertices.row(sphere.faces(f, 0)).transpose(),
                          b = sphere.vertices.row(sphere.faces(f, 1)).transpose(),
                          c = sphere.vertices.row(sphere.faces(f, 2)).transpose();
    const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
    const double inradius = (b - a).cross(c - a).norm() / perimeter;
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d x = (a + b + c) / 3 - 0.1 * inradius * unit(random) * n - 1e-3 * inradius * n;
    const Eigen::Vector3d g = gradient(x);
    EXPECT_NEAR(g.norm(), 1.0, 1e-6);
    EXPECT_NEAR(g.dot(n), 1.0, 1e-6); // along the outward face normal
  }
}

TEST(MeshSignedDistance, UpdateFollowsMovedPositionsAndSurfacesOfALargerModel) {
  // A surface whose vertices are rows 10.. of a larger position matrix, moved between queries.
  const Mesh sphere = icosphere(1, 1.0);
  std::vector<std::array<int, 3>> triangles;
  for (Eigen::Index f = 0; f < sphere.faces.rows(); ++f)
    triangles.push_back({10 + sphere.faces(f, 0), 10 + sphere.faces(f, 1), 10 + sphere.faces(f, 2)});
  Eigen::MatrixX3d positions = Eigen::MatrixX3d::Constant(10 + sphere.vertices.rows(), 3, 1e3);
  positions.bottomRows(sphere.vertices.rows()) = sphere.vertices;
  SignedDistanceMesh mesh(triangles);
  mesh.update(positions);
  EXPECT_LT(mesh.signed_distance(Eigen::Vector3d::Zero()), 0.0);
  EXPECT_TRUE(mesh.in_bounds(Eigen::Vector3d::Zero()));
  positions.bottomRows(sphere.vertices.rows()).rowwise() += Eigen::RowVector3d(5, 0, 0);
  mesh.update(positions);
  EXPECT_GT(mesh.signed_distance(Eigen::Vector3d::Zero()), 3.0);
  EXPECT_FALSE(mesh.in_bounds(Eigen::Vector3d::Zero()));
  EXPECT_LT(mesh.signed_distance(Eigen::Vector3d(5, 0, 0)), -0.5);
}

TEST(MeshSignedDistance, ALargeMeshIsSearchedLikeAScanAndSignedByItsPseudonormals) {
  // 81920 triangles, a deep search tree: the organs' tessellations that landmarks search have
  // millions.
  const double r = 30.0;
  const Mesh sphere = icosphere(6, r);
  ASSERT_GT(sphere.faces.rows(), 80000);
  const SignedDistanceMesh scanned = distance_mesh(sphere, false), tree = distance_mesh(sphere, true);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> radius(0.0, 2.0 * r);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d x = radius(random) * random_direction(random);
    const MeshClosestPoint expected = scanned.closest(x), found = tree.closest(x);
    EXPECT_EQ(found.triangle, expected.triangle) << x.transpose();
    EXPECT_EQ(found.distance_squared, expected.distance_squared) << x.transpose();
    EXPECT_EQ(tree.signed_distance(x), scanned.signed_distance(x)) << x.transpose();
  }
  // Just off vertices and edge midpoints, where the sign comes from the vertices' and edges'
  // pseudonormals: every edge and vertex of the large mesh is connected to its neighbours.
  for (Eigen::Index f = 0; f < sphere.faces.rows(); f += 97) {
    const Eigen::Vector3d a = sphere.vertices.row(sphere.faces(f, 0)).transpose(),
                          b = sphere.vertices.row(sphere.faces(f, 1)).transpose();
    for (const Eigen::Vector3d& p : {a, Eigen::Vector3d((a + b) / 2)}) {
      for (double step : {-1e-6, 1e-6}) {
        const Eigen::Vector3d x = p + step * p.normalized();
        EXPECT_EQ(tree.signed_distance(x) < 0.0, step < 0.0) << x.transpose();
      }
    }
  }
}

TEST(MeshSignedDistance, AHintedSearchGivesTheSameAnswerTiesIncluded) {
  // Any hint (near, far, out of range) leaves the answer closest(x)'s. Vertices and edge
  // midpoints are ties between triangles: the lowest index wins with or without a hint.
  const Mesh sphere = icosphere(4, 20.0);
  const SignedDistanceMesh tree = distance_mesh(sphere, true);
  const auto faces = static_cast<int>(sphere.faces.rows());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> radius(0.0, 40.0);
  std::uniform_int_distribution<int> hint(-1, faces);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 300; ++i)
    points.push_back(radius(random) * random_direction(random));
  for (Eigen::Index f = 0; f < sphere.faces.rows(); f += 37) {
    points.push_back(sphere.vertices.row(sphere.faces(f, 0)).transpose() * 1.01);
    points.push_back(
        0.5 *
        (sphere.vertices.row(sphere.faces(f, 0)) + sphere.vertices.row(sphere.faces(f, 1))).transpose());
  }
  int previous = -1;
  for (const Eigen::Vector3d& x : points) {
    const MeshClosestPoint expected = tree.closest(x);
    for (const int h : {hint(random), previous, expected.triangle, faces + 5}) {
      const MeshClosestPoint found = tree.closest(x, h);
      EXPECT_EQ(found.triangle, expected.triangle) << x.transpose() << " hint " << h;
      EXPECT_EQ(found.distance_squared, expected.distance_squared) << x.transpose() << " hint " << h;
    }
    previous = expected.triangle;
  }
}

TEST(MeshSignedDistance, ABlockSearchGivesEachPointTheTreesAnswerTiesIncluded) {
  // Blocks of points as the level sets search them (a box of voxels, then each voxel among the
  // triangles near_box() gathered): on the surface, across it, inside and far outside, and
  // blocks holding vertices and edge midpoints, where triangles tie and the lowest index wins.
  const Mesh sphere = icosphere(4, 20.0);
  const SignedDistanceMesh tree = distance_mesh(sphere, true);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> radius(0.0, 40.0), size(0.0, 6.0), unit(0.0, 1.0);
  SignedDistanceMesh::NearTriangles near;
  std::size_t gathered = 0;
  int blocks = 0;
  const auto check_block = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                               const std::vector<Eigen::Vector3d>& extra) {
    tree.near_box(lo, hi, near);
    gathered += near.entries.size();
    ++blocks;
    std::vector<Eigen::Vector3d> points = extra;
    for (int i = 0; i < 20; ++i)
      points.push_back(lo +
                       (hi - lo).cwiseProduct(Eigen::Vector3d(unit(random), unit(random), unit(random))));
    for (int corner = 0; corner < 8; ++corner)
      points.emplace_back((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                          (corner & 4) ? hi.z() : lo.z());
    for (const Eigen::Vector3d& x : points) {
      const MeshClosestPoint expected = tree.closest(x), found = tree.closest(x, near);
      ASSERT_EQ(found.triangle, expected.triangle) << x.transpose();
      EXPECT_EQ(found.distance_squared, expected.distance_squared) << x.transpose();
      EXPECT_EQ(found.on_triangle.point, expected.on_triangle.point) << x.transpose();
      EXPECT_EQ(found.on_triangle.feature, expected.on_triangle.feature) << x.transpose();
    }
  };
  for (int b = 0; b < 200; ++b) {
    const Eigen::Vector3d lo = radius(random) * random_direction(random);
    check_block(lo, lo + Eigen::Vector3d(size(random), size(random), size(random)), {});
  }
  for (Eigen::Index f = 0; f < sphere.faces.rows(); f += 41) {
    const Eigen::Vector3d a = sphere.vertices.row(sphere.faces(f, 0)).transpose(),
                          b = sphere.vertices.row(sphere.faces(f, 1)).transpose();
    const Eigen::Vector3d middle = 0.5 * (a + b);
    check_block(a.cwiseMin(middle) - Eigen::Vector3d::Constant(1.0),
                a.cwiseMax(middle) + Eigen::Vector3d::Constant(1.0), {a, middle, 1.01 * a, 0.99 * middle});
  }
  // Without a search tree nothing is gathered, and each point is searched as closest(x) does.
  const SignedDistanceMesh scanned = distance_mesh(sphere, false);
  scanned.near_box(Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0), near);
  EXPECT_TRUE(near.entries.empty());
  for (const Eigen::Vector3d& x : {Eigen::Vector3d(0.5, -0.5, 0.0), Eigen::Vector3d(19.0, 1.0, 0.5)}) {
    EXPECT_EQ(scanned.closest(x, near).triangle, tree.closest(x).triangle) << x.transpose();
    EXPECT_EQ(scanned.closest(x, near).distance_squared, tree.closest(x).distance_squared) << x.transpose();
  }
  // The point of blocks: each gathers a small part of the mesh.
  EXPECT_LT(static_cast<double>(gathered) / blocks, 0.25 * static_cast<double>(sphere.faces.rows()));
}
