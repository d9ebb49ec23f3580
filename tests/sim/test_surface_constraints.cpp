// Surface constraints (edge strain, triangle strain and area, bending): projections land in their sets
// and are the closest points, the energy's gradient matches finite differences, bending
// vanishes on rigid motions and grows with the square of a fold, and a hanging sheet solved by
// local/global reaches Newton's minimizer.

#include "anatomy/structured_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/sim_settings.hpp"
#include "sim/surface_constraints.hpp"
#include "tests/support/finite_difference.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <cstdio>
#include <limits>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

Eigen::Matrix3d random_rotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random))
      .normalized()
      .toRotationMatrix();
}

/// Two triangles (0 1 2) and (1 0 3) sharing the edge 0-1, folded by `angle` about it.
Eigen::MatrixX3d hinge(double angle) {
  Eigen::MatrixX3d x(4, 3);
  x << 0, 0, 0, 1, 0, 0, 0.4, 0.8, 0, 0.6, -0.7, 0;
  x(3, 1) = -0.7 * std::cos(angle);
  x(3, 2) = 0.7 * std::sin(angle);
  return x;
}

/// A sheet of 0.2 x 0.2 m in the x-z plane, its top row (z max) held, under gravity along -z.
ElasticModel hanging_sheet(int cells) {
  const TriangleMesh mesh =
      structured_sheet({200, 200}, {cells, cells}, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  ElasticModel model;
  // The sheet lies in the x-y plane: turn it upright (y -> z).
  Eigen::MatrixX3d rest(mesh.vertices.rows(), 3);
  rest.col(0) = 1e-3 * mesh.vertices.col(0);
  rest.col(1) = 1e-3 * mesh.vertices.col(2);
  rest.col(2) = 1e-3 * mesh.vertices.col(1);
  add_sheet(model, rest, mesh.faces, 1e5, 0.3, 300.0, 1e-3);
  const double top = rest.col(2).maxCoeff();
  for (Eigen::Index v = 0; v < rest.rows(); ++v)
    if (rest(v, 2) > top - 1e-9) model.fixed[static_cast<std::size_t>(v)] = 1;
  model.external_forces_N = Eigen::MatrixX3d::Zero(rest.rows(), 3);
  model.external_forces_N.col(2) = -9.81 * model.masses_kg;
  return model;
}

} // namespace

TEST(SurfaceConstraints, ProjectionsLandInTheirSetsAndAreTheClosestPoints) {
  std::mt19937 random(9);
  std::normal_distribution<double> normal;
  Eigen::MatrixX3d rest(4, 3);
  rest << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.2, 0.5;
  const SingularValueRange limits{0.9, 1.1};
  const SurfaceElement edge = edge_strain_element(0, 1, rest, 10.0, limits);
  const SurfaceElement triangle = triangle_strain_element({0, 1, 2}, rest, 5.0, limits);
  for (int trial = 0; trial < 300; ++trial) {
    SurfaceMatrix F;
    for (int i = 0; i < 6; ++i)
      F(i) = (trial % 3 == 0 ? 0.1 : 1.0) * normal(random);
    // Edge: the length clamped, the direction kept.
    SurfaceMatrix T = project_surface(edge, F);
    EXPECT_GE(T.col(0).norm(), 0.9 - 1e-12);
    EXPECT_LE(T.col(0).norm(), 1.1 + 1e-12);
    EXPECT_LT((T.col(0).normalized() - F.col(0).normalized()).norm(), 1e-12);
    // Triangle: singular values clamped; against Eigen's SVD.
    T = project_surface(triangle, F);
    const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(F, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::Vector2d clamped = svd.singularValues().cwiseMax(0.9).cwiseMin(1.1);
    const SurfaceMatrix reference = svd.matrixU() * clamped.asDiagonal() * svd.matrixV().transpose();
    EXPECT_LT((T - reference).norm(), 1e-9 * (1.0 + F.norm())) << F;
    const Eigen::Vector2d values = Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(T).singularValues();
    EXPECT_GE(values.minCoeff(), 0.9 - 1e-9);
    EXPECT_LE(values.maxCoeff(), 1.1 + 1e-9);
    // No point of the set sampled nearby is closer.
    for (int k = 0; k < 5; ++k) {
      const Eigen::Matrix3d turn =
          Eigen::AngleAxisd(0.05 * normal(random), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const SurfaceMatrix other = turn * T; // same singular values: in the set
      EXPECT_LE((F - T).norm(), (F - other).norm() + 1e-12);
    }
  }
  // Triangle area: the product of the singular values clamped, at the closest such point
  // (against a fine search along the hyperbola s1 s2 = P).
  const SurfaceElement area = triangle_area_element({0, 1, 2}, rest, 3.0, limits);
  for (int trial = 0; trial < 100; ++trial) {
    SurfaceMatrix F;
    for (int i = 0; i < 6; ++i)
      F(i) = normal(random);
    const SurfaceMatrix T = project_surface(area, F);
    const Eigen::Vector2d sigma = Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(F).singularValues();
    const Eigen::Vector2d values = Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(T).singularValues();
    const double product = values.prod();
    EXPECT_GE(product, 0.9 * (1 - 1e-9));
    EXPECT_LE(product, 1.1 * (1 + 1e-9));
    if (sigma.prod() >= 0.9 && sigma.prod() <= 1.1) {
      EXPECT_LT((T - F).norm(), 1e-9);
      continue;
    }
    const double P = sigma.prod() < 0.9 ? 0.9 : 1.1;
    double best = std::numeric_limits<double>::infinity();
    for (double t = -8.0; t <= 8.0; t += 1e-4) { // s = (sqrt(P) e^t, sqrt(P) e^-t)
      best = std::min(
          best, std::hypot(sigma[0] - std::sqrt(P) * std::exp(t), sigma[1] - std::sqrt(P) * std::exp(-t)));
    }
    EXPECT_NEAR((F - T).norm(), best, 1e-6) << sigma.transpose();
  }
  // A collapsed triangle (rank 1 or 0) still gets a target in the set.
  for (const SurfaceMatrix& F :
       {SurfaceMatrix::Zero().eval(), (SurfaceMatrix() << 1, 2, 0, 0, 0, 0).finished()}) {
    const SurfaceMatrix T = project_surface(triangle, F);
    const Eigen::Vector2d values = Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(T).singularValues();
    EXPECT_NEAR(values.minCoeff(), 0.9, 1e-12);
  }
}

TEST(SurfaceConstraints, BendingVanishesOnRigidMotionsAndGrowsWithTheSquareOfAFold) {
  const Eigen::MatrixX3d flat = hinge(0.0);
  const SurfaceElement bend = bending_element({0, 1, 2, 3}, flat, 1.0);
  EXPECT_LT(bend.rest.norm(), 1e-12); // the cotangent Laplacian of a flat patch vanishes
  std::mt19937 random(2);
  const Eigen::Matrix3d R = random_rotation(random);
  const Eigen::MatrixX3d moved = (flat * R.transpose()).rowwise() + Eigen::RowVector3d(0.3, -1, 2);
  EXPECT_LT(surface_deformation(bend, moved).norm(), 1e-12);
  auto energy = [&](const SurfaceElement& e, const Eigen::MatrixX3d& x) {
    const SurfaceMatrix F = surface_deformation(e, x);
    return 0.5 * e.weight * (F - project_surface(e, F)).squaredNorm();
  };
  const double small = energy(bend, hinge(0.01)), twice = energy(bend, hinge(0.02));
  EXPECT_GT(small, 0.0);
  EXPECT_NEAR(twice / small, 4.0, 1e-3);
  // A curved rest state: its rigid motions cost nothing either; flattening it does.
  const SurfaceElement curved = bending_element({0, 1, 2, 3}, hinge(0.5), 1.0);
  EXPECT_GT(curved.rest.norm(), 0.1);
  EXPECT_LT(energy(curved, (hinge(0.5) * R.transpose()).rowwise() + Eigen::RowVector3d(1, 2, 3)), 1e-20);
  EXPECT_GT(energy(curved, flat), 1e-3);
}

TEST(SurfaceConstraints, SheetEnergyGradientMatchesFiniteDifferences) {
  ElasticModel model = hanging_sheet(3);
  std::mt19937 random(4);
  std::normal_distribution<double> normal;
  Eigen::MatrixX3d p = model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      p(v, c) += 0.02 * normal(random);
  const StepInertia none;
  const Eigen::MatrixX3d numeric = central_difference_gradient(
      [&](const Eigen::MatrixX3d& x) { return model_energy(model, none, x); }, p, 1e-7);
  EXPECT_TRUE(matches_finite_differences(model_gradient(model, none, p), numeric, 1e-5));
}

// A sheet hanging from its top edge under gravity (quasi-static): local/global and Newton
// (Gauss-Newton for surface elements) reach the same minimizer; the energy never rises.
TEST(SurfaceConstraints, HangingSheetLocalGlobalReachesTheNewtonMinimizer) {
  const ElasticModel model = hanging_sheet(4);
  Eigen::MatrixX3d newton = model.rest_positions_m;
  StopCriteria tight;
  tight.max_iterations = 500;
  tight.gradient_norm_N = 1e-11;
  const SolveReport reference = newton_solve(model, StepInertia{}, newton, tight);
  EXPECT_LT(reference.residual_N, 1e-10) << reference.iterations;
  const double scale = (newton - model.rest_positions_m).norm();
  ASSERT_GT(scale, 1e-4);
  LocalGlobalSolver solver(model, 0.0, 1);
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 5000;
  stop.relative_energy_decrease = 0.0;
  stop.position_change_m = 1e-14;
  // as tight as the comparison below: the residual test alone would stop at 1e-3
  stop.relative_residual = 1e-12;
  const SolveReport report = solver.solve(p, Eigen::MatrixX3d(), stop, true);
  std::printf("hanging sheet: Newton %d iterations, local/global %d (%s), sag %.3g mm\n",
              reference.iterations, report.iterations, report.stopped_by.c_str(),
              1e3 * (model.rest_positions_m.col(2).minCoeff() - p.col(2).minCoeff()));
  EXPECT_LT((p - newton).norm(), 1e-6 * scale) << report.iterations << " " << report.stopped_by;
  for (std::size_t k = 1; k < report.energies_J.size(); ++k)
    ASSERT_LE(report.energies_J[k], report.energies_J[k - 1] * (1.0 + 1e-12) + 1e-15) << k;
  // It sags: the bottom edge moved down, the held top stayed.
  EXPECT_LT(p.col(2).minCoeff(), model.rest_positions_m.col(2).minCoeff() - 1e-4);
}

// A sheet held at two neighbouring corners falls and swings under gravity (cloth.yaml in small):
// Newton, with the membrane's Hessian w (I - dP/dF) projected onto the PSD cone, converges every
// frame to the default tolerance (a thousandth of a vertex's weight) within a few dozen
// iterations. With the Gauss-Newton matrix w I instead it crawled where the sheet folds, one
// inertia-sized step at a time, hundreds of iterations per frame.
TEST(SurfaceConstraints, SwingingSheetNewtonConvergesInFewIterations) {
  const TriangleMesh mesh =
      structured_sheet({200, 200}, {8, 8}, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  ElasticModel model;
  add_sheet(model, 1e-3 * mesh.vertices, mesh.faces, 1e6, 0.3, 300.0, 5e-4);
  const Eigen::MatrixX3d& rest = model.rest_positions_m;
  const double top = rest.col(1).maxCoeff(), side = rest.col(0).maxCoeff();
  double weight_N = 0.0;
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    if (rest(v, 1) > top - 1e-9 && std::abs(rest(v, 0)) > side - 1e-9)
      model.fixed[static_cast<std::size_t>(v)] = 1;
    weight_N = std::max(weight_N, 9.81 * model.masses_kg[v]);
  }
  const double h = 1.0 / 60.0;
  StopCriteria stop;
  stop.max_iterations = 40;
  stop.relative_residual = SolverSettings{}.relative_residual_tolerance;
  stop.force_scale_N = weight_N;
  Eigen::MatrixX3d p = rest, velocity = Eigen::MatrixX3d::Zero(rest.rows(), 3);
  int most = 0;
  for (int frame = 0; frame < 15; ++frame) {
    StepInertia inertia;
    inertia.weight = 1.0 / (h * h);
    inertia.target_m = p + h * velocity;
    inertia.target_m.col(2).array() -= h * h * 9.81;
    const Eigen::MatrixX3d previous = p;
    const SolveReport report = newton_solve(model, inertia, p, stop);
    EXPECT_TRUE(report.converged) << "frame " << frame << ": relative residual " << report.relative_residual;
    most = std::max(most, report.iterations);
    velocity = (p - previous) / h;
  }
  std::printf("swinging sheet: at most %d Newton iterations per frame, lowest point %.1f mm\n", most,
              1e3 * p.col(2).minCoeff());
  EXPECT_LT(p.col(2).minCoeff(), -0.05); // it fell and swung
}

// Shells at the extremes: Young's modulus 1 Pa to 1 GPa, thickness 1 um to 10 mm, time steps
// 1e-5 s to 1 s, with and without gravity, from a start with collapsed (zero-area), flipped and
// bent triangles: finite results, and the energy never rising over local/global iterations.
TEST(SurfaceConstraints, ShellsAreStableAtTheExtremesFromCollapsedStarts) {
  const TriangleMesh mesh =
      structured_sheet({100, 100}, {6, 6}, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  for (double E : {1.0, 1e9}) {
    for (double thickness : {1e-6, 1e-2}) {
      for (double h : {1e-5, 1.0}) {
        for (double gravity : {9.81, 0.0}) {
          SCOPED_TRACE("E " + std::to_string(E) + " t " + std::to_string(thickness) + " h " +
                       std::to_string(h) + " g " + std::to_string(gravity));
          ElasticModel model;
          add_sheet(model, 1e-3 * mesh.vertices, mesh.faces, E, 0.3, 1000.0, thickness);
          model.fixed[0] = 1; // one corner held
          Eigen::MatrixX3d start = model.rest_positions_m;
          for (Eigen::Index v = 1; v < start.rows(); ++v) {
            if (v % 5 == 0) start.row(v) = start.row(v - 1); // collapse triangles
            if (v % 7 == 0) start(v, 0) = -start(v, 0);      // flip others
            if (v % 3 == 0) start(v, 2) = 0.01;              // out of the plane
          }
          const double weight = 1.0 / (h * h);
          Eigen::MatrixX3d target = start;
          target.col(2).array() -= h * h * gravity;
          LocalGlobalSolver solver(model, weight, 1);
          Eigen::MatrixX3d p = start;
          StopCriteria stop;
          stop.max_iterations = 200;
          stop.relative_energy_decrease = 0.0;
          stop.position_change_m = 0.0;
          const SolveReport report = solver.solve(p, target, stop, true);
          ASSERT_TRUE(p.allFinite());
          ASSERT_TRUE(std::isfinite(report.final_energy_J));
          for (std::size_t k = 1; k < report.energies_J.size(); ++k)
            ASSERT_LE(report.energies_J[k], report.energies_J[k - 1] * (1.0 + 1e-12) + 1e-300) << k;
        }
      }
    }
  }
}
