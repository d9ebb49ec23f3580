// The patch volume constraint: the enclosed volume and its gradient, the projection onto a
// volume range, and shells that keep their volume under load in every solver.

#include "geometry/triangle_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/enclosed_volume.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

/// A closed sphere of radius r (metres) as a constraint's surface, with random bump heights
/// (bumps: true) or flat patches.
struct Balloon {
  Eigen::MatrixX3d rest_m;
  std::vector<int> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<double> heights;
};

Balloon balloon(int level, double radius_m, bool bumps) {
  const TriangleMesh sphere = unit_icosphere(level);
  Balloon b;
  b.rest_m = radius_m * sphere.vertices;
  for (Eigen::Index v = 0; v < sphere.vertices.rows(); ++v)
    b.vertices.push_back(static_cast<int>(v));
  std::mt19937 random(3);
  std::uniform_real_distribution<double> height(0.0, 0.02 * radius_m);
  for (Eigen::Index t = 0; t < sphere.face_count(); ++t) {
    b.triangles.push_back({sphere.faces(t, 0), sphere.faces(t, 1), sphere.faces(t, 2)});
    if (bumps) b.heights.push_back(height(random));
  }
  return b;
}

EnclosedVolume constraint_of(const Balloon& b, double bulk_modulus, const SingularValueRange& range) {
  return enclosed_volume_constraint(b.vertices, b.triangles, b.heights, b.rest_m, bulk_modulus, range);
}

} // namespace

TEST(EnclosedVolume, ACubeWithBumpsEnclosesItsVolumePlusHeightTimesArea) {
  // The unit cube's 12 outward triangles (side s), each patch with bump height h.
  const double s = 0.03, h = 1e-3;
  Eigen::MatrixX3d corners(8, 3);
  for (int k = 0; k < 8; ++k)
    corners.row(k) = s * Eigen::RowVector3d(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  const std::vector<std::array<int, 3>> triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                                     {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                                     {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  const EnclosedVolume flat =
      enclosed_volume_constraint({0, 1, 2, 3, 4, 5, 6, 7}, triangles, {}, corners, 1e6);
  EXPECT_NEAR(flat.rest_volume_m3, s * s * s, 1e-18);
  const EnclosedVolume bumpy = enclosed_volume_constraint({0, 1, 2, 3, 4, 5, 6, 7}, triangles,
                                                          std::vector<double>(12, h), corners, 1e6);
  EXPECT_NEAR(bumpy.rest_volume_m3, s * s * s + 6.0 * s * s * h, 1e-18);
  // Translations change nothing; an inward surface is refused.
  Eigen::MatrixX3d moved = corners;
  moved.rowwise() += Eigen::RowVector3d(0.1, -0.2, 0.3);
  EXPECT_NEAR(enclosed_volume(bumpy, moved), bumpy.rest_volume_m3, 1e-17);
  std::vector<std::array<int, 3>> inward = triangles;
  for (auto& t : inward)
    std::swap(t[1], t[2]);
  EXPECT_THROW(enclosed_volume_constraint({0, 1, 2, 3, 4, 5, 6, 7}, inward, {}, corners, 1e6),
               std::invalid_argument);
}

TEST(EnclosedVolume, GradientMatchesFiniteDifferences) {
  const Balloon b = balloon(1, 0.02, true);
  const EnclosedVolume c = constraint_of(b, 1e6, {});
  std::mt19937 random(8);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::MatrixX3d X = b.rest_m;
  for (Eigen::Index i = 0; i < X.size(); ++i)
    X.data()[i] += normal(random);
  const Eigen::MatrixX3d numeric =
      central_difference_gradient([&](const Eigen::MatrixX3d& Y) { return enclosed_volume(c, Y); }, X, 1e-7);
  EXPECT_TRUE(matches_finite_differences(enclosed_volume_gradient(c, X), numeric, 1e-7));
}

TEST(EnclosedVolume, ProjectionLandsOnTheNearerLimitAtTheClosestPoint) {
  const Balloon b = balloon(2, 0.02, true);
  const EnclosedVolume c = constraint_of(b, 1e6, {0.99, 1.01});
  const double V0 = c.rest_volume_m3;
  // Inside the range: unchanged.
  const Eigen::MatrixX3d slightly = 1.002 * b.rest_m;
  EXPECT_EQ(project_enclosed_volume(c, slightly), slightly);
  // Squashed along z (V about 0.8 V0) and blown up (1.1^3): onto 0.99 V0 and 1.01 V0.
  Eigen::MatrixX3d squashed = b.rest_m;
  squashed.col(2) *= 0.8;
  for (const auto& [X, limit] :
       {std::pair{squashed, 0.99}, std::pair{Eigen::MatrixX3d(1.1 * b.rest_m), 1.01}}) {
    const Eigen::MatrixX3d Y = project_enclosed_volume(c, X);
    EXPECT_NEAR(enclosed_volume(c, Y), limit * V0, 1e-12 * V0);
    // The Lagrange condition: Y - X is a multiple of grad V(Y).
    const Eigen::MatrixX3d G = enclosed_volume_gradient(c, Y);
    const Eigen::MatrixX3d d = Y - X;
    const double mu = d.cwiseProduct(G).sum() / G.squaredNorm();
    EXPECT_LT((d - mu * G).norm(), 1e-9 * d.norm());
    // Closer than the uniform scaling about the centroid that reaches the same volume.
    const Eigen::RowVector3d centre = X.colwise().mean();
    double lo = 0.5, hi = 2.0;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      const Eigen::MatrixX3d scaled = (mid * (X.rowwise() - centre)).rowwise() + centre;
      (enclosed_volume(c, scaled) < limit * V0 ? lo : hi) = mid;
    }
    const Eigen::MatrixX3d scaled = (lo * (X.rowwise() - centre)).rowwise() + centre;
    EXPECT_LT(d.norm(), (scaled - X).norm());
  }
}

namespace {

/// A closed shell (E 10 kPa, nu 0.3, 1 mm thick) with an enclosed volume kept within
/// `tolerance`, its bottom cap held and its top cap moved down by `press_m` (prescribed), or
/// pressed by a plate that has come down that far.
ElasticModel pressed_balloon(double tolerance, double press_m, bool with_volume, bool plate = false) {
  const Balloon b = balloon(2, 0.02, false);
  const TriangleMesh sphere = unit_icosphere(2);
  ElasticModel model;
  add_sheet(model, b.rest_m, sphere.faces, 1e4, 0.3, 1000.0, 1e-3);
  if (with_volume)
    model.volumes.push_back(constraint_of(b, 1e4 / (3.0 * (1.0 - 0.6)), {1.0 - tolerance, 1.0 + tolerance}));
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v) {
    const double z = model.rest_positions_m(v, 2);
    if (z < -0.018 || (!plate && z > 0.018)) model.fixed[static_cast<std::size_t>(v)] = 1;
  }
  if (plate) {
    Obstacle o;
    o.point_m = Eigen::Vector3d(0.0, 0.0, 0.02 - press_m);
    o.normal = -Eigen::Vector3d::UnitZ();
    model.obstacles.push_back(o);
    model.contact_stiffness_N_m = 1e3;
  }
  return model;
}

/// Rest positions with the top cap moved down by press_m.
Eigen::MatrixX3d pressed_start(const ElasticModel& model, double press_m) {
  Eigen::MatrixX3d p = model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    if (p(v, 2) > 0.018) p(v, 2) -= press_m;
  return p;
}

double shell_volume(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  const TriangleMesh sphere = unit_icosphere(2);
  TriangleMesh deformed = sphere;
  deformed.vertices = p;
  return enclosed_volume(deformed);
}

} // namespace

TEST(EnclosedVolume, APressedBalloonKeepsItsVolumeAndBulgesWhereAnEmptyShellCaves) {
  for (const bool with_volume : {true, false}) {
    const ElasticModel model = pressed_balloon(0.005, 0.008, with_volume);
    LocalGlobalSolver solver(model, 0.0, 2, 5);
    Eigen::MatrixX3d p = pressed_start(model, 0.008);
    StopCriteria stop;
    stop.max_iterations = 3000;
    stop.relative_energy_decrease = 1e-12;
    stop.position_change_m = 1e-12;
    stop.relative_residual = 1e-12; // the gradient check below asks for the minimizer itself
    const SolveReport report = solver.solve(p, Eigen::MatrixX3d(), stop, true);
    ASSERT_TRUE(p.allFinite());
    for (std::size_t k = 1; k < report.energies_J.size(); ++k)
      ASSERT_LE(report.energies_J[k], report.energies_J[k - 1] * (1.0 + 1e-12)) << k;
    const double V0 = shell_volume(model, model.rest_positions_m), V = shell_volume(model, p);
    const double width = p.col(0).maxCoeff() - p.col(0).minCoeff();
    if (with_volume) {
      EXPECT_NEAR(V / V0, 1.0, 0.01) << report.iterations << " iterations";
      EXPECT_GT(width, 0.0405) << width; // pressed 8 mm (20 %) from above, it bulges sideways
      // The minimizer: the gradient (of the exact energy, the volume term included) vanishes.
      EXPECT_LT(free_gradient_norm(model, model_gradient(model, {}, p)),
                1e-6 * report.initial_energy_J / 0.008)
          << report.stopped_by;
    } else {
      EXPECT_LT(V / V0, 0.97) << V / V0; // nothing holds the volume: it loses 4.6 %
    }
  }
}

TEST(EnclosedVolume, EnergyGradientMatchesFiniteDifferencesThroughTheProjection) {
  ElasticModel model = pressed_balloon(0.01, 0.0, true);
  model.obstacles.clear();
  std::mt19937 random(4);
  std::normal_distribution<double> normal(0.0, 2e-4);
  Eigen::MatrixX3d p = 0.97 * model.rest_positions_m; // below the range: the constraint acts
  for (Eigen::Index i = 0; i < p.size(); ++i)
    p.data()[i] += normal(random);
  const StepInertia none;
  const Eigen::MatrixX3d g = model_gradient(model, none, p);
  // Every seventh coordinate: each difference costs two evaluations of the whole model.
  std::vector<Eigen::Index> coordinates;
  for (Eigen::Index i = 0; i < p.size(); i += 7)
    coordinates.push_back(i);
  const Eigen::VectorXd numeric = central_difference_gradient(
      [&](const Eigen::MatrixX3d& x) { return model_energy(model, none, x); }, p, 1e-8, coordinates);
  EXPECT_TRUE(matches_finite_differences(g.reshaped()(coordinates), numeric, 1e-5, g.cwiseAbs().maxCoeff()));
}

TEST(EnclosedVolume, NewtonAndXpbdHoldTheVolumeToo) {
  const ElasticModel model = pressed_balloon(0.005, 0.008, true, true); // by a plate
  {
    Eigen::MatrixX3d p = model.rest_positions_m;
    StopCriteria stop;
    stop.max_iterations = 400;
    stop.gradient_norm_N = 1e-9;
    stop.relative_energy_decrease = -1.0;
    stop.position_change_m = -1.0;
    newton_solve(model, {}, p, stop);
    ASSERT_TRUE(p.allFinite());
    EXPECT_NEAR(shell_volume(model, p) / shell_volume(model, model.rest_positions_m), 1.0, 0.01);
  }
  {
    // Dynamic steps of 10 ms under XPBD: finite, and the volume held.
    StepInertia inertia;
    inertia.weight = 1e4;
    Eigen::MatrixX3d p = model.rest_positions_m;
    for (int frame = 0; frame < 10; ++frame) {
      inertia.target_m = p;
      StopCriteria stop;
      stop.max_iterations = 50;
      position_based_solve(PositionBasedVariant::xpbd, model, inertia, p, stop);
    }
    ASSERT_TRUE(p.allFinite());
    EXPECT_NEAR(shell_volume(model, p) / shell_volume(model, model.rest_positions_m), 1.0, 0.02);
  }
}
