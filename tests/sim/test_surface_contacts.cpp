// Contacts between bodies' surfaces: the inside test and closest point against a closed surface,
// and two bodies pressed together that do not pass through each other.

#include "anatomy/structured_mesh.hpp"
#include "geometry/tet_boundary.hpp"
#include "geometry/triangle_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/surface_contacts.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

ContactSurface surface_of(const Eigen::MatrixX3i& faces, int first_vertex) {
  ContactSurface s;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    s.triangles.push_back(
        {first_vertex + faces(f, 0), first_vertex + faces(f, 1), first_vertex + faces(f, 2)});
    for (int k = 0; k < 3; ++k)
      s.vertices.push_back(first_vertex + faces(f, k));
  }
  std::sort(s.vertices.begin(), s.vertices.end());
  s.vertices.erase(std::unique(s.vertices.begin(), s.vertices.end()), s.vertices.end());
  return s;
}

} // namespace

TEST(SurfaceContacts, InsideTestAndClosestPointAgainstAClosedSurface) {
  const TriangleMesh sphere = unit_icosphere(2); // inscribed in the unit sphere
  const std::vector<ContactSurface> surfaces = {surface_of(sphere.faces, 0)};
  ContactGeometry geometry(surfaces);
  geometry.update(sphere.vertices);
  std::mt19937 random(2);
  std::normal_distribution<double> normal;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(normal(random), normal(random), normal(random)).normalized();
    // Inside everywhere below the inscribed radius of the faces, outside beyond 1; the points
    // along vertex directions test the corner pseudonormals.
    const double radius = k % 3 == 0 ? 0.9 : k % 3 == 1 ? 1.05 : 0.5;
    const Eigen::Vector3d x =
        radius * (k % 10 == 0 ? Eigen::Vector3d(sphere.vertices.row(k % sphere.vertices.rows()).transpose())
                              : direction);
    const SurfaceQuery q = geometry.query(0, x);
    ASSERT_EQ(q.inside, radius < 1.0) << x.transpose() << " radius " << radius << " k " << k << " closest "
                                      << q.closest.transpose() << " distance " << q.distance;
    if (radius > 1.0 && !q.inside && q.distance == 0.0) continue; // outside the bounds: no search
    // The closest point lies on the surface (between the inscribed radius and 1) and no vertex is closer.
    EXPECT_LE(q.closest.norm(), 1.0 + 1e-12);
    EXPECT_GE(q.closest.norm(), 0.95);
    for (Eigen::Index v = 0; v < sphere.vertices.rows(); ++v)
      ASSERT_LE(q.distance, (x - sphere.vertices.row(v).transpose()).norm() + 1e-12);
    EXPECT_NEAR(q.normal.norm(), 1.0, 1e-12);
    if (q.inside) {
      EXPECT_GT(q.normal.dot(x), 0.0); // outward
    }
  }
}

namespace {

/// Two cubes 1 mm apart along x (E 10 kPa, nu 0.3), A of 10 mm facing the middle of B's 20 mm
/// face: A's far face is moved +2.5 mm towards B (prescribed), B's far face is held.
struct TwoCubes {
  ElasticModel model;
  Eigen::MatrixX3d start;
};

TwoCubes two_cubes(bool contacts) {
  TwoCubes t;
  for (int side : {-1, 1}) {
    // A 10 mm cube (3 cells a side) against the middle of a 20 mm one's face (5 cells), off
    // centre: no vertex meets another.
    const TetMesh cube = side < 0 ? structured_box({10, 10, 10}, {3, 3, 3}, Eigen::Matrix3d::Identity(),
                                                   Eigen::Vector3d(-5.5, 1.3, -0.7))
                                  : structured_box({20, 20, 20}, {5, 5, 5}, Eigen::Matrix3d::Identity(),
                                                   Eigen::Vector3d(10.5, 0, 0));
    const Eigen::MatrixX3d rest = 1e-3 * cube.vertices;
    const int first = add_body(t.model, rest, cube.tets, lame_parameters(1e4, 0.3), 1000.0);
    t.model.contact_surfaces.push_back(surface_of(tet_boundary_faces(cube.vertices, cube.tets), first));
  }
  if (contacts) t.model.contact_pairs.push_back({0, 1});
  t.model.contact_stiffness_N_m = 1e5;
  t.start = t.model.rest_positions_m;
  for (Eigen::Index v = 0; v < t.start.rows(); ++v) {
    const double x = t.start(v, 0);
    if (x < -0.0104) {
      t.model.fixed[static_cast<std::size_t>(v)] = 1;
      t.start(v, 0) += 0.0025;
    } else if (x > 0.0204) {
      t.model.fixed[static_cast<std::size_t>(v)] = 1;
    }
  }
  return t;
}

/// The deepest any vertex of one cube lies inside the other.
double penetration(const TwoCubes& t, const Eigen::MatrixX3d& p) {
  ContactGeometry geometry(t.model.contact_surfaces);
  geometry.update(p);
  double deepest = 0.0;
  for (int s = 0; s < 2; ++s)
    for (int v : t.model.contact_surfaces[static_cast<std::size_t>(s)].vertices) {
      const SurfaceQuery q = geometry.query(1 - s, p.row(v).transpose());
      if (q.inside) deepest = std::max(deepest, q.distance);
    }
  return deepest;
}

} // namespace

TEST(SurfaceContacts, PressedCubesDoNotPassThroughEachOther) {
  for (const bool contacts : {false, true}) {
    const TwoCubes t = two_cubes(contacts);
    LocalGlobalSolver solver(t.model, 0.0, 2, 5);
    Eigen::MatrixX3d p = t.start;
    StopCriteria stop;
    stop.max_iterations = contacts ? 3000 : 300; // without contacts a short solve shows the overlap
    stop.relative_energy_decrease = 1e-12;
    stop.position_change_m = 1e-12;
    const SolveReport report = solver.solve(p, Eigen::MatrixX3d(), stop);
    ASSERT_TRUE(p.allFinite());
    // B's near face (rest x = 0.5 mm) is pushed only through the contact: how far its most
    // pushed vertex went.
    double b_near = 0.0;
    for (int v : t.model.contact_surfaces[1].vertices)
      if (t.model.rest_positions_m(v, 0) < 0.0006) b_near = std::max(b_near, p(v, 0));
    if (contacts) {
      EXPECT_GT(report.contacts, 10);
      EXPECT_LT(penetration(t, p), 1e-6) << report.iterations << " iterations, " << report.stopped_by;
      EXPECT_GT(b_near, 0.0005 + 0.0005); // indented by more than 0.5 mm of the 1.5 mm overlap
      // Newton on the same energy (vertex-to-surface penalties both ways) converges to its
      // minimizer; local/global approaches it slowly where vertices slide along the other surface
      // (a contact holds its vertex to the closest point of the last local step: sliding gains
      // (elastic force / kc) per iteration): 3000 iterations come within 0.25 % in energy.
      Eigen::MatrixX3d q = t.start;
      StopCriteria newton_stop;
      newton_stop.max_iterations = 200;
      newton_stop.gradient_norm_N = 1e-9;
      newton_stop.relative_energy_decrease = -1.0;
      newton_stop.position_change_m = -1.0;
      const SolveReport newton = newton_solve(t.model, {}, q, newton_stop);
      EXPECT_EQ(newton.stopped_by, "gradient");
      EXPECT_LT(penetration(t, q), 1e-6);
      EXPECT_NEAR(report.final_energy_J / newton.final_energy_J, 1.0, 0.005);
      EXPECT_LT((p - q).cwiseAbs().maxCoeff(), 0.15e-3);
      std::printf("cubes: local/global %d iterations, energy %.4f %% above Newton's (%d iterations), "
                  "positions within %.3f mm\n",
                  report.iterations, 100.0 * (report.final_energy_J / newton.final_energy_J - 1.0),
                  newton.iterations, 1e3 * (p - q).cwiseAbs().maxCoeff());
    } else {
      EXPECT_GT(penetration(t, p), 1e-3); // A passes 1.5 mm into B
      EXPECT_NEAR(b_near, 0.0005, 1e-9);
    }
  }
}

TEST(SurfaceContacts, XpbdKeepsTheCubesApart) {
  TwoCubes t = two_cubes(true);
  StepInertia inertia;
  inertia.weight = 1.0 / (0.01 * 0.01);
  Eigen::MatrixX3d p = t.model.rest_positions_m;
  for (int frame = 1; frame <= 10; ++frame) {
    inertia.target_m = p; // at rest between frames (no velocity carried: a slow push)
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      if (t.model.fixed[static_cast<std::size_t>(v)] && t.model.rest_positions_m(v, 0) < 0.0)
        p(v, 0) = t.model.rest_positions_m(v, 0) + 0.0025 * frame / 10.0;
    StopCriteria stop;
    stop.max_iterations = 40;
    position_based_solve(PositionBasedVariant::xpbd, t.model, inertia, p, stop);
  }
  ASSERT_TRUE(p.allFinite());
  EXPECT_LT(penetration(t, p), 3e-4);
}

TEST(SurfaceContacts, ContactEnergyGradientMatchesFiniteDifferences) {
  // The cubes overlapping by 1.5 mm (A moved rigidly into B): vertices of each inside the other.
  const TwoCubes t = two_cubes(true);
  Eigen::MatrixX3d p = t.model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    if (p(v, 0) < 0.0) p(v, 0) += 0.0025;
  std::mt19937 random(6);
  std::normal_distribution<double> normal(0.0, 1e-5);
  for (Eigen::Index i = 0; i < p.size(); ++i)
    p.data()[i] += normal(random);
  const std::vector<SurfaceContact> contacts = surface_contacts(t.model, p);
  ASSERT_GT(contacts.size(), 10u);
  // The coordinates the contacts touch: their vertices and the triangles they lie on.
  std::vector<Eigen::Index> touched;
  for (const SurfaceContact& c : contacts) {
    touched.push_back(c.vertex);
    for (int v : c.query.triangle)
      touched.push_back(v);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  std::vector<Eigen::Index> coordinates; // one per free vertex
  for (const Eigen::Index v : touched)
    if (!t.model.fixed[static_cast<std::size_t>(v)]) coordinates.push_back(v + p.rows() * (v % 3));
  const Eigen::MatrixX3d g = model_gradient(t.model, {}, p);
  const Eigen::VectorXd numeric = central_difference_gradient(
      [&](const Eigen::MatrixX3d& x) { return model_energy(t.model, {}, x); }, p, 1e-9, coordinates);
  EXPECT_TRUE(matches_finite_differences(g.reshaped()(coordinates), numeric, 1e-6, g.cwiseAbs().maxCoeff()));
}
