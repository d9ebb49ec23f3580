// Collision with rigid obstacles (half-space, ball): projections, the penalty's gradient, the
// factor's rank updates and downdates, and solves that press a cantilever against obstacles.

#include "anatomy/structured_mesh.hpp"
#include "sim/build_model.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/obstacles.hpp"
#include "sim/position_based.hpp"
#include "sim/sim_settings.hpp"
#include "sim/sparse_cholesky.hpp"
#include "tests/support/finite_difference.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cstring>

#include <cstdio>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

Obstacle plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  Obstacle o;
  o.shape = Obstacle::Shape::half_space;
  o.point_m = point;
  o.normal = normal.normalized();
  return o;
}

Obstacle ball(const Eigen::Vector3d& centre, double radius) {
  Obstacle o;
  o.shape = Obstacle::Shape::sphere;
  o.point_m = centre;
  o.radius_m = radius;
  return o;
}

/// A cantilever 20 x 20 x 100 mm along z, its z = 0 end clamped, under gravity along -y:
/// quasi-static (it sags about 9 mm at the tip without obstacles).
ElasticModel cantilever(double youngs_modulus_Pa = 2e4) {
  const TetMesh mesh =
      structured_box({20, 20, 100}, {2, 2, 10}, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 50));
  ElasticModel model;
  add_body(model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(youngs_modulus_Pa, 0.3), 1000.0);
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    if (model.rest_positions_m(v, 2) < 1e-9) model.fixed[static_cast<std::size_t>(v)] = 1;
  model.external_forces_N = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  model.external_forces_N.col(1) = -9.81 * model.masses_kg;
  return model;
}

double deepest_penetration(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  double deepest = 0.0;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    for (const Obstacle& o : model.obstacles)
      deepest = std::max(deepest, -o.signed_distance(p.row(v).transpose()));
  return deepest;
}

struct Solved {
  Eigen::MatrixX3d p;
  SolveReport report;
};

Solved solve_local_global(const ElasticModel& model, const Eigen::MatrixX3d& start, int anderson = 5) {
  LocalGlobalSolver solver(model, 0.0, 1, anderson);
  Solved s{start, {}};
  StopCriteria stop;
  stop.max_iterations = 20000;
  stop.relative_energy_decrease = 0.0;
  stop.position_change_m = 1e-12;
  // as tight as the comparison below: the residual test alone would stop at 1e-3
  stop.relative_residual = 1e-12;
  s.report = solver.solve(s.p, Eigen::MatrixX3d(), stop);
  return s;
}

Solved solve_newton(const ElasticModel& model, const Eigen::MatrixX3d& start) {
  Solved s{start, {}};
  StopCriteria stop;
  stop.max_iterations = 200;
  stop.gradient_norm_N = 1e-10;
  s.report = newton_solve(model, StepInertia{}, s.p, stop);
  return s;
}

} // namespace

TEST(Obstacles, ProjectionsLandOnTheBoundaryAndLeaveAllowedPointsAlone) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  for (const Obstacle& o : {plane(Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1, 2, -0.5)),
                            ball(Eigen::Vector3d(0.2, 0, -0.1), 1.3)}) {
    for (int trial = 0; trial < 500; ++trial) {
      const Eigen::Vector3d x(uniform(random), uniform(random), uniform(random));
      const Eigen::Vector3d projected = o.project(x);
      if (o.signed_distance(x) >= 0.0) {
        EXPECT_EQ(projected, x);
        EXPECT_DOUBLE_EQ(contact_energy({o}, 7.0, x), 0.0);
      } else {
        EXPECT_NEAR(o.signed_distance(projected), 0.0, 1e-14);
        // The closest allowed point: the step is along the normal, as long as the depth.
        EXPECT_NEAR((x - projected).norm(), -o.signed_distance(x), 1e-14);
        EXPECT_LT(((projected - x).normalized() - o.outward_normal(x)).norm(), 1e-12);
      }
    }
  }
  // On the boundary nothing moves; the centre of a ball goes out along +z.
  const Obstacle b = ball(Eigen::Vector3d::Zero(), 2.0);
  EXPECT_EQ(b.project(Eigen::Vector3d(0, 2, 0)), Eigen::Vector3d(0, 2, 0));
  EXPECT_EQ(b.project(Eigen::Vector3d::Zero()), Eigen::Vector3d(0, 0, 2));
}

TEST(Obstacles, ContactGradientMatchesFiniteDifferences) {
  const std::vector<Obstacle> obstacles = {plane(Eigen::Vector3d(0, 0, 0.2), Eigen::Vector3d(0.3, -0.2, 1)),
                                           ball(Eigen::Vector3d(0.5, 0.1, 0), 0.8)};
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.5);
  const double k = 3.5e3, h = 1e-6;
  int inside = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3d x(uniform(random), uniform(random), uniform(random));
    // Errors relative to k at least: the gradient is k times a depth, often zero outside.
    const Eigen::Vector3d numeric = central_difference_gradient(
        [&](const Eigen::Vector3d& y) { return contact_energy(obstacles, k, y); }, x, h);
    EXPECT_TRUE(matches_finite_differences(contact_gradient(obstacles, k, x), numeric, 1e-6, k))
        << x.transpose();
    // Along each contact's normal the Hessian is exact (the ball's negative curvature across
    // its normal is what the positive semi-definite Hessian leaves out).
    for (const Obstacle& o : obstacles) {
      if (o.signed_distance(x) >= -2 * h) continue;
      ++inside;
      const std::vector<Obstacle> one = {o};
      const Eigen::Vector3d n = o.outward_normal(x);
      const Eigen::Vector3d along_normal = directional_difference(
          [&](const Eigen::Vector3d& y) { return contact_gradient(one, k, y); }, x, n, h);
      EXPECT_TRUE(matches_finite_differences(contact_hessian(one, k, x) * n, along_normal, 1e-5, k));
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(contact_hessian(obstacles, k, x))
                    .eigenvalues()
                    .minCoeff(),
                -1e-9);
    }
  }
  EXPECT_GT(inside, 50);
}

namespace {

/// The lower triangle of the 1-D Laplacian plus a small diagonal, n rows.
Eigen::SparseMatrix<double> laplacian(int n) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 2.01);
    if (i > 0) entries.emplace_back(i, i - 1, -1.0);
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}

} // namespace

TEST(SparseCholesky, DiagonalRankUpdatesAndDowndatesEqualANewFactorization) {
  const int n = 200;
  const Eigen::SparseMatrix<double> A = laplacian(n);
  Eigen::MatrixX3d b = Eigen::MatrixX3d::Random(n, 3);
  SparseCholesky factor(A);
  Eigen::MatrixX3d before, x, reference;
  factor.solve(b, before);

  std::vector<std::pair<int, double>> changes = {{3, 50.0}, {77, 1e4}, {150, 0.5}, {199, 2.0}};
  factor.update_diagonal(changes);
  Eigen::SparseMatrix<double> changed = A;
  for (const auto& [row, delta] : changes)
    changed.coeffRef(row, row) += delta;
  SparseCholesky fresh(changed);
  factor.solve(b, x);
  fresh.solve(b, reference);
  EXPECT_LT((x - reference).norm(), 1e-10 * reference.norm());
  EXPECT_GT((x - before).norm(), 1e-3 * before.norm()); // the change mattered

  // Take some back and add others in one call: downdates and updates together.
  factor.update_diagonal({{3, -50.0}, {77, -1e4}, {10, 5.0}});
  changed.coeffRef(3, 3) -= 50.0;
  changed.coeffRef(77, 77) -= 1e4;
  changed.coeffRef(10, 10) += 5.0;
  SparseCholesky fresh2(changed);
  factor.solve(b, x);
  fresh2.solve(b, reference);
  EXPECT_LT((x - reference).norm(), 1e-10 * reference.norm());
  EXPECT_EQ(factor.rank_changes(), 7);

  Eigen::SparseMatrix<double> indefinite = A;
  indefinite.coeffRef(5, 5) = -1.0;
  EXPECT_THROW(SparseCholesky{indefinite}, std::runtime_error);
}

TEST(SparseCholesky, ColumnUpdatesThatFillInAndTheTwoThreadSolveAreExact) {
  // 5000 rows (enough for the split solve), changed by c c^T with c coupling far-apart rows (a
  // contact between two bodies): new entries of L.
  const int n = 5000;
  const Eigen::SparseMatrix<double> A = laplacian(n);
  const Eigen::MatrixX3d b = Eigen::MatrixX3d::Random(n, 3);
  SparseCholesky factor(A);
  const SparseCholesky::Column c = {{10, 30.0}, {2000, -12.0}, {4500, -18.0}};
  factor.update_columns({c}, {});
  Eigen::MatrixXd dense_c = Eigen::MatrixXd::Zero(n, 1);
  for (const auto& [row, value] : c)
    dense_c(row, 0) = value;
  const Eigen::SparseMatrix<double> cc = (dense_c * dense_c.transpose()).sparseView();
  const Eigen::SparseMatrix<double> changed =
      Eigen::SparseMatrix<double>(A + Eigen::SparseMatrix<double>(cc.triangularView<Eigen::Lower>()));
  SparseCholesky fresh(changed);
  Eigen::MatrixX3d x, reference;
  factor.solve(b, x);
  fresh.solve(b, reference);
  EXPECT_LT((x - reference).norm(), 1e-10 * reference.norm());
  // Two threads: the same bits.
  Eigen::MatrixX3d split;
  factor.solve(b, split, 2);
  EXPECT_EQ(std::memcmp(x.data(), split.data(), sizeof(double) * static_cast<std::size_t>(x.size())), 0);
  // And back.
  factor.update_columns({}, {c});
  SparseCholesky original(A);
  factor.solve(b, x);
  original.solve(b, reference);
  EXPECT_LT((x - reference).norm(), 1e-10 * reference.norm());
  EXPECT_EQ(factor.rank_changes(), 2);
}

namespace {

/// The lower triangle of the 3-D grid Laplacian (7-point) plus a small diagonal, n^3 rows: a
/// compact body's pattern, whose factor fills in as a tet mesh's does.
Eigen::SparseMatrix<double> grid_laplacian(int n) {
  std::vector<Eigen::Triplet<double>> entries;
  const auto row = [n](int i, int j, int k) { return (k * n + j) * n + i; };
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        entries.emplace_back(row(i, j, k), row(i, j, k), 6.01);
        if (i > 0) entries.emplace_back(row(i, j, k), row(i - 1, j, k), -1.0);
        if (j > 0) entries.emplace_back(row(i, j, k), row(i, j - 1, k), -1.0);
        if (k > 0) entries.emplace_back(row(i, j, k), row(i, j, k - 1), -1.0);
      }
    }
  }
  Eigen::SparseMatrix<double> A(n * n * n, n * n * n);
  A.setFromTriplets(entries.begin(), entries.end());
  return A;
}

} // namespace

TEST(SparseCholesky, TheSupernodalFactorSolvesAndUpdatesAsTheSimplicialOne) {
  // 18^3 = 5832 rows: above k_supernodal_rows, so `automatic` factors supernodally.
  const Eigen::SparseMatrix<double> A = grid_laplacian(18);
  ASSERT_GE(A.rows(), SparseCholesky::k_supernodal_rows);
  const Eigen::MatrixX3d b = Eigen::MatrixX3d::Random(A.rows(), 3);
  SparseCholesky simplicial(A, SparseCholesky::Factorization::simplicial);
  SparseCholesky supernodal(A);
  Eigen::MatrixX3d x, reference;
  simplicial.solve(b, reference);
  supernodal.solve(b, x);
  EXPECT_LT((x - reference).norm(), 1e-12 * reference.norm());
  // The residual of the supernodal factor's solve is as small as the simplicial one's.
  const Eigen::SparseMatrix<double> full = Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Lower>());
  EXPECT_LT((full * x - b).norm(), 1e-12 * b.norm());
  // Rank changes work on the converted factor: a contact's column and the diagonal, then back.
  const SparseCholesky::Column c = {{10, 3.0}, {3000, -1.2}, {5800, -1.8}};
  supernodal.update_columns({c}, {});
  supernodal.update_diagonal({{100, 40.0}});
  simplicial.update_columns({c}, {});
  simplicial.update_diagonal({{100, 40.0}});
  simplicial.solve(b, reference);
  supernodal.solve(b, x);
  EXPECT_LT((x - reference).norm(), 1e-12 * reference.norm());
  supernodal.update_columns({}, {c});
  supernodal.update_diagonal({{100, -40.0}});
  SparseCholesky original(A, SparseCholesky::Factorization::simplicial);
  original.solve(b, reference);
  supernodal.solve(b, x);
  EXPECT_LT((x - reference).norm(), 1e-12 * reference.norm());
  // An indefinite matrix is refused the same way.
  Eigen::SparseMatrix<double> indefinite = A;
  indefinite.coeffRef(5, 5) = -10.0;
  EXPECT_THROW(SparseCholesky(indefinite, SparseCholesky::Factorization::supernodal), std::runtime_error);
}

TEST(SparseCholesky, AFactorOfTheLastAnalysedPatternIsTheFactorOfANewAnalysis) {
  // Simplicial (1-D, 300 rows) and supernodal (3-D grid, 5832 rows) analyses.
  for (const Eigen::SparseMatrix<double>& A : {laplacian(300), grid_laplacian(18)}) {
    Eigen::SparseMatrix<double> other_values = A; // the same pattern, other values
    for (Eigen::Index k = 0; k < other_values.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(other_values, k); it; ++it)
        it.valueRef() *= it.row() == it.col() ? 1.5 + 1e-3 * static_cast<double>(k % 7) : 0.9;
    const Eigen::MatrixX3d b = Eigen::MatrixX3d::Random(A.rows(), 3);
    const long before = SparseCholesky::analyses();
    SparseCholesky first(A);
    EXPECT_EQ(SparseCholesky::analyses(), before + 1);
    Eigen::MatrixX3d copied, fresh;
    {
      SparseCholesky again(other_values); // the last analysis, copied
      EXPECT_EQ(SparseCholesky::analyses(), before + 1);
      again.solve(b, copied);
    }
    // Another pattern (one entry more) is analysed, and then so is the first one again.
    Eigen::SparseMatrix<double> wider = A;
    wider.coeffRef(A.rows() - 1, 0) = -1e-3;
    wider.makeCompressed();
    SparseCholesky other(wider);
    EXPECT_EQ(SparseCholesky::analyses(), before + 2);
    SparseCholesky analysed(other_values);
    EXPECT_EQ(SparseCholesky::analyses(), before + 3);
    analysed.solve(b, fresh);
    // The same factor: the same bits.
    EXPECT_EQ(
        std::memcmp(copied.data(), fresh.data(), sizeof(double) * static_cast<std::size_t>(copied.size())),
        0);
    const Eigen::SparseMatrix<double> full =
        Eigen::SparseMatrix<double>(other_values.selfadjointView<Eigen::Lower>());
    EXPECT_LT((full * copied - b).norm(), 1e-10 * b.norm());
  }
}

// A cantilever sagging onto a table (a half-space) below its free half: local/global with
// contacts that come during the solve reaches Newton's minimizer of the same energy, nothing
// sinks into the table deeper than the penalty's own tolerance, and the table carries the part
// of the weight the clamp does not.
TEST(LocalGlobalContacts, CantileverRestingOnATableReachesTheNewtonMinimizer) {
  ElasticModel model = cantilever();
  model.obstacles = {plane(Eigen::Vector3d(0, -0.014, 0), Eigen::Vector3d(0, 1, 0))};
  model.contact_stiffness_N_m = 1e4;
  const Solved free = solve_local_global(cantilever(), model.rest_positions_m);
  ASSERT_LT(free.p.col(1).minCoeff(), -0.016); // without the table it would go through

  const Solved lg = solve_local_global(model, model.rest_positions_m);
  const Solved newton = solve_newton(model, model.rest_positions_m);
  EXPECT_LT(newton.report.residual_N, 1e-9);
  const double scale = (newton.p - model.rest_positions_m).norm();
  EXPECT_LT((lg.p - newton.p).norm(), 1e-6 * scale) << lg.report.iterations << " " << lg.report.stopped_by;
  EXPECT_NEAR(lg.report.final_energy_J, newton.report.final_energy_J,
              1e-8 * std::abs(newton.report.final_energy_J));
  EXPECT_GT(lg.report.contacts, 0);
  EXPECT_GT(lg.report.rank_updates, 0);
  EXPECT_LT(lg.report.residual_N, 1e-6) << lg.report.stopped_by << " after " << lg.report.iterations;
  // Penetration is what the penalty needs to push back: force / k, far below a millimetre.
  const double depth = deepest_penetration(model, lg.p);
  EXPECT_GT(depth, 0.0);
  EXPECT_LT(depth, 2e-4);
  // The table's push equals the contact forces k * depth summed.
  double table_force = 0.0;
  for (Eigen::Index v = 0; v < lg.p.rows(); ++v)
    table_force +=
        contact_gradient(model.obstacles, model.contact_stiffness_N_m, lg.p.row(v).transpose()).norm();
  EXPECT_GT(table_force, 0.05 * 9.81 * model.masses_kg.sum());
  EXPECT_LT(table_force, 9.81 * model.masses_kg.sum());
}

// A ball pressed down into the top of the cantilever's free end: the same minimizer from
// local/global (plain and with Anderson) and Newton; Jacobi + Chebyshev comes close.
TEST(LocalGlobalContacts, BallPressedIntoTheBarAgreesAcrossSolvers) {
  ElasticModel model = cantilever(5e4);
  model.external_forces_N.setZero();
  model.obstacles = {ball(Eigen::Vector3d(0, 0.025, 0.09), 0.02)}; // reaches 5 mm into the top
  model.contact_stiffness_N_m = 1e5;
  const Solved newton = solve_newton(model, model.rest_positions_m);
  EXPECT_LT(newton.report.residual_N, 1e-9);
  const double scale = (newton.p - model.rest_positions_m).norm();
  ASSERT_GT(scale, 1e-3);
  for (int anderson : {0, 5}) {
    const Solved lg = solve_local_global(model, model.rest_positions_m, anderson);
    EXPECT_LT((lg.p - newton.p).norm(), 1e-6 * scale)
        << "anderson " << anderson << ": " << lg.report.iterations;
    EXPECT_GT(lg.report.contacts, 0);
    EXPECT_LT(deepest_penetration(model, lg.p), 2e-4);
  }
  LocalGlobalSolver solver(model, 0.0, 1);
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 10000;
  stop.relative_energy_decrease = 0.0;
  stop.position_change_m = 1e-13;
  // as tight as the comparison below: the residual test alone would stop at 1e-3
  stop.relative_residual = 1e-12;
  const SolveReport jacobi = solver.solve_jacobi_chebyshev(p, Eigen::MatrixX3d(), stop);
  std::printf("jacobi: %d iterations, stopped by %s, relative error %.3g\n", jacobi.iterations,
              jacobi.stopped_by.c_str(), (p - newton.p).norm() / scale);
  // Jacobi's one sweep per iteration lets vertices at the ball's surface chatter in and out of
  // contact: it stalls near 2e-4 of the displacement (local/global, which solves exactly, does
  // not).
  EXPECT_LT((p - newton.p).norm(), 1e-3 * scale);
}

// A bar squeezed between two frictionless paddles, as a breast in mammography: the material
// under the paddles must slide out along them. The global step stiffens a vertex in contact
// along the paddle's normal only, so local/global reaches the default tolerance (a thousandth of
// the force that moves a vertex by the paddles' travel) within a few dozen iterations and lands
// on Newton's minimizer; with the contact stiffness in every direction (the vertex pinned
// where it was) it slid by force / kc per iteration and stalled near 2 % of that force.
TEST(LocalGlobalContacts, MaterialSlidesAlongFrictionlessPaddles) {
  ElasticModel model = cantilever();
  model.external_forces_N.setZero();
  const double travel = 0.002; // each paddle 2 mm into the 20 mm wide bar
  model.obstacles = {plane(Eigen::Vector3d(0.01 - travel, 0, 0), Eigen::Vector3d(-1, 0, 0)),
                     plane(Eigen::Vector3d(-0.01 + travel, 0, 0), Eigen::Vector3d(1, 0, 0))};
  model.contact_stiffness_N_m =
      1e4 * sim_detail::nominal_stiffness(model); // as the deformation stage sets it
  StopCriteria stop;                              // the scene defaults (sim/load_schedule.cpp)
  stop.max_iterations = SolverSettings{}.max_iterations;
  stop.relative_residual = SolverSettings{}.relative_residual_tolerance;
  stop.force_scale_N = sim_detail::nominal_stiffness(model) * travel;
  LocalGlobalSolver solver(model, 0.0, 1);
  Eigen::MatrixX3d p = model.rest_positions_m;
  const SolveReport lg = solver.solve(p, Eigen::MatrixX3d(), stop);
  const Solved newton = solve_newton(model, model.rest_positions_m);
  std::printf("paddles: local/global %d iterations, relative residual %.3g, %d contacts\n", lg.iterations,
              lg.relative_residual, lg.contacts);
  EXPECT_TRUE(lg.converged) << lg.relative_residual;
  EXPECT_LT(lg.iterations, 200);
  EXPECT_GT(lg.contacts, 0);
  // It bulged out of the paddles' way (along y and z, sliding along them), where Newton has it.
  const double bulge = p.col(1).maxCoeff() - model.rest_positions_m.col(1).maxCoeff();
  EXPECT_GT(bulge, 1e-4);
  const double scale = (newton.p - model.rest_positions_m).norm();
  EXPECT_LT((p - newton.p).norm(), 1e-2 * scale);
}

// Contacts also go: a start pushed into the table, with nothing pressing the bar down, ends
// with no contact, exactly where the bar goes without the table.
TEST(LocalGlobalContacts, ContactsThatNoLongerPressAreReleased) {
  ElasticModel model = cantilever();
  model.external_forces_N.col(1) *= -1.0; // "gravity" upward: the bar lifts off
  model.obstacles = {plane(Eigen::Vector3d(0, -0.0101, 0), Eigen::Vector3d(0, 1, 0))};
  model.contact_stiffness_N_m = 1e4;
  Eigen::MatrixX3d start = model.rest_positions_m;
  for (Eigen::Index v = 0; v < start.rows(); ++v)
    if (!model.fixed[static_cast<std::size_t>(v)]) start(v, 1) -= 0.004 * start(v, 2) / 0.1; // into the table
  ASSERT_GT(deepest_penetration(model, start), 0.003);
  ElasticModel without = model;
  without.obstacles.clear();
  const Solved lifted = solve_local_global(model, start);
  const Solved reference = solve_local_global(without, start);
  EXPECT_EQ(lifted.report.contacts, 0);
  EXPECT_GT(lifted.report.contact_changes, 0);
  EXPECT_GT(lifted.report.rank_updates, 0);
  EXPECT_LT((lifted.p - reference.p).norm(), 1e-8 * (reference.p - start).norm());
}

// The position-based solvers see the obstacles too: one dynamic step of the cantilever with a
// ball pushed into its top, by XPBD (contacts with compliance 1/kc) and hard PBD projections.
TEST(PositionBasedContacts, XpbdAndPbdPushVerticesOutOfAnObstacle) {
  ElasticModel model = cantilever(5e4);
  model.external_forces_N.setZero();
  model.obstacles = {ball(Eigen::Vector3d(0, 0.025, 0.09), 0.02)};
  model.contact_stiffness_N_m = 1e5;
  StepInertia step;
  step.weight = 1.0 / (0.01 * 0.01);
  step.target_m = model.rest_positions_m;
  ASSERT_GT(deepest_penetration(model, model.rest_positions_m), 0.004);
  for (const PositionBasedVariant variant :
       {PositionBasedVariant::xpbd, PositionBasedVariant::gauss_seidel_pbd}) {
    Eigen::MatrixX3d p = model.rest_positions_m;
    StopCriteria stop;
    stop.max_iterations = 300;
    stop.relative_energy_decrease = 0.0;
    stop.position_change_m = 0.0;
    position_based_solve(variant, model, step, p, stop);
    ASSERT_TRUE(p.allFinite());
    EXPECT_LT(deepest_penetration(model, p), 5e-4)
        << (variant == PositionBasedVariant::xpbd ? "xpbd" : "pbd");
  }
}
