// The position-based solvers on the model's constraints: XPBD approaches the minimizer of the
// step's energy that Newton finds; Gauss-Seidel PBD lands in every constraint set when they
// intersect; both stay finite at the extremes and refuse quasi-static solves.

#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/twisting_bar.hpp"

#include <gtest/gtest.h>

#include <cstdio>

using namespace phantasm;

namespace {

TwistingBarStep coarse_bar(double youngs_modulus_Pa = 1e5) {
  TwistingBarSettings settings;
  settings.cells = {3, 3, 12};
  settings.size_mm = {60, 60, 240};
  settings.youngs_modulus_Pa = youngs_modulus_Pa;
  return twisting_bar_step(settings);
}

/// Largest distance of a tet's deformation gradient to its strain or volume set.
double largest_violation(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  double largest = 0.0;
  for (const TetElement& e : model.tets) {
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    const SignedSvd svd = signed_svd(deformation_gradient(e, p), rotation);
    largest = std::max({largest, (svd.sigma - project_strain(svd.sigma, model.strain_range)).norm(),
                        (svd.sigma - project_volume(svd.sigma, model.volume_range)).norm()});
  }
  return largest;
}

StopCriteria iterations_only(int count) {
  StopCriteria stop;
  stop.max_iterations = count;
  stop.relative_energy_decrease = 0.0;
  stop.position_change_m = 0.0;
  return stop;
}

} // namespace

// XPBD on the coarse twisting bar: its energy error falls by orders of magnitude toward
// Newton's minimizer, and its positions approach it (XPBD's fixed point is not exactly the
// minimizer where the constraint gradients turn during the step).
TEST(Xpbd, CoarseTwistingBarApproachesTheNewtonMinimizer) {
  const TwistingBarStep bar = coarse_bar();
  Eigen::MatrixX3d newton = bar.start_m;
  StopCriteria tight;
  tight.max_iterations = 40;
  tight.gradient_norm_N = 1e-10;
  const SolveReport reference = newton_solve(bar.model, bar.inertia, newton, tight);
  const double E_star = reference.final_energy_J;
  const double E_0 = model_energy(bar.model, bar.inertia, bar.start_m);
  const double r_0 = (bar.start_m - newton).norm();

  Eigen::MatrixX3d p = bar.start_m;
  const SolveReport report = position_based_solve(PositionBasedVariant::xpbd, bar.model, bar.inertia, p,
                                                  iterations_only(1000), true);
  ASSERT_TRUE(p.allFinite());
  const double energy_error = (report.final_energy_J - E_star) / (E_0 - E_star);
  const double position_error = (p - newton).norm() / r_0;
  std::printf("XPBD after %d sweeps: energy error %.3g, position error %.3g\n", report.iterations,
              energy_error, position_error);
  EXPECT_LT(energy_error, 1e-2);
  EXPECT_GT(energy_error, -1e-9); // never below the minimum
  EXPECT_LT(position_error, 0.1);
  EXPECT_EQ(report.solver, "xpbd");
}

// Hard constraints that can all hold (only one end of a short bar clamped, no twist): Gauss-
// Seidel PBD projects every tet back to a rotation of unit volume, whatever its stiffness. (On
// long bars it gets there slowly: each sweep carries a correction only so far along the bar.)
TEST(GaussSeidelPbd, LandsInEveryConstraintSetWhenTheyIntersect) {
  TwistingBarSettings settings;
  settings.cells = {2, 2, 4};
  settings.size_mm = {40, 40, 80};
  TwistingBarStep bar = twisting_bar_step(settings);
  Eigen::MatrixX3d p = bar.start_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (bar.model.rest_positions_m(v, 2) > 0.0)
      bar.model.fixed[static_cast<std::size_t>(v)] = 0; // free the turned end
    if (!bar.model.fixed[static_cast<std::size_t>(v)]) p(v, 1) = 0.7 * bar.inertia.target_m(v, 1); // squashed
  }
  const double before = largest_violation(bar.model, p);
  ASSERT_GT(before, 0.2);
  const SolveReport report = position_based_solve(PositionBasedVariant::gauss_seidel_pbd, bar.model,
                                                  bar.inertia, p, iterations_only(2000));
  ASSERT_TRUE(p.allFinite());
  EXPECT_LT(largest_violation(bar.model, p), 1e-6) << before << " at the start";
  EXPECT_EQ(report.solver, "gauss_seidel_pbd");
}

// Young's modulus 1 Pa to 1 GPa and time steps 1e-5 s to 1 s: finite results, finite energies.
TEST(PositionBased, FiniteAtTheExtremesAndRefusesQuasiStaticSolves) {
  for (const PositionBasedVariant variant :
       {PositionBasedVariant::xpbd, PositionBasedVariant::gauss_seidel_pbd}) {
    for (double E : {1.0, 1e9}) {
      for (double h : {1e-5, 1.0}) {
        TwistingBarSettings settings;
        settings.size_mm = {20, 20, 80};
        settings.cells = {2, 2, 8};
        settings.youngs_modulus_Pa = E;
        settings.poisson_ratio = 0.499;
        settings.time_step_s = h;
        const TwistingBarStep bar = twisting_bar_step(settings);
        Eigen::MatrixX3d p = bar.start_m;
        const SolveReport report =
            position_based_solve(variant, bar.model, bar.inertia, p, iterations_only(50));
        EXPECT_TRUE(p.allFinite()) << E << " " << h;
        EXPECT_TRUE(std::isfinite(report.final_energy_J));
        EXPECT_TRUE(std::isfinite(report.residual_N));
      }
    }
  }
  const TwistingBarStep bar = coarse_bar();
  Eigen::MatrixX3d p = bar.start_m;
  try {
    position_based_solve(PositionBasedVariant::xpbd, bar.model, StepInertia{}, p, iterations_only(5));
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("xpbd steps in time"), std::string::npos);
  }
}
