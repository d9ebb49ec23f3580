// The extremes table (#16, docs/deformation.md): a representative subset of its rows, each solver
// on the cantilever at an extreme Young's modulus, Poisson ratio, time step or a load that
// inverts it. Every row is a converged answer within 1 % of Newton's converged field, or a
// warning (not converged, or inverted tets): never a silent wrong field. The whole table is
// bench/solver_extremes.cpp.

#include "bench/solver_extremes.hpp"

#include <gtest/gtest.h>

#include <optional>

using namespace phantasm;
using namespace phantasm::bench;

namespace {

/// Runs the solvers on a case and checks the property; returns the verdicts. Position-based
/// solvers are cut at `position_based_iterations` sweeps (a sweep costs far more than a
/// local/global iteration here; the property holds at any limit).
std::vector<Verdict> expect_converged_or_warned(const ExtremeCase& c,
                                                const std::vector<ExtremeSolver>& solvers,
                                                int position_based_iterations = 200) {
  const ExtremeCantilever k = extreme_cantilever(c);
  std::optional<ExtremeOracle> oracle; // only for rows the stage would not warn about
  std::vector<Verdict> verdicts;
  for (ExtremeSolver solver : solvers) {
    StopCriteria stop = k.stop;
    if (solver == ExtremeSolver::xpbd || solver == ExtremeSolver::gauss_seidel_pbd)
      stop.max_iterations = position_based_iterations;
    ExtremeRow row = run_extreme(c, solver, k, stop);
    if (row.verdict == Verdict::no_oracle) {
      if (!oracle) oracle = extreme_oracle(k);
      EXPECT_TRUE(oracle_converged(*oracle)) << oracle->report.relative_residual;
      judge_extreme(row, k, *oracle);
    }
    SCOPED_TRACE(std::string(to_string(solver)) + ": " + std::to_string(row.report.iterations) +
                 " iterations, relative residual " + std::to_string(row.report.relative_residual) + ", " +
                 std::to_string(row.inverted.inverted) + " inverted, tip " + std::to_string(row.tip_mm) +
                 " mm, field error " + std::to_string(row.field_error));
    EXPECT_TRUE(row.verdict == Verdict::converged_and_right || row.verdict == Verdict::warned)
        << to_string(row.verdict) << " " << row.error;
    verdicts.push_back(row.verdict);
  }
  return verdicts;
}

} // namespace

TEST(SolverExtremes, StiffCantileverConvergesToNewtonsField) {
  const auto v =
      expect_converged_or_warned({1e9, 0.3, 0.0, 0.0}, {ExtremeSolver::local_global, ExtremeSolver::newton});
  EXPECT_EQ(v[1], Verdict::converged_and_right);
}

TEST(SolverExtremes, SoftCantileverThatInvertsIsWarned) {
  const auto v =
      expect_converged_or_warned({1e3, 0.3, 0.0, 0.0}, {ExtremeSolver::local_global, ExtremeSolver::newton});
  EXPECT_EQ(v[0], Verdict::warned);
  EXPECT_EQ(v[1], Verdict::warned);
}

TEST(SolverExtremes, NearlyIncompressibleCantileverConvergesOrWarns) {
  const auto v = expect_converged_or_warned({1e5, 0.4999, 0.0, 0.0},
                                            {ExtremeSolver::local_global, ExtremeSolver::newton});
  EXPECT_EQ(v[1], Verdict::converged_and_right);
}

TEST(SolverExtremes, TinyTimeStepEverySolver) {
  expect_converged_or_warned({1e5, 0.3, 1e-6, 0.0},
                             {ExtremeSolver::local_global, ExtremeSolver::jacobi_chebyshev,
                              ExtremeSolver::newton, ExtremeSolver::xpbd, ExtremeSolver::gauss_seidel_pbd});
}

TEST(SolverExtremes, ModerateTimeStepEverySolver) {
  expect_converged_or_warned({1e5, 0.3, 1e-2, 0.0},
                             {ExtremeSolver::local_global, ExtremeSolver::jacobi_chebyshev,
                              ExtremeSolver::newton, ExtremeSolver::xpbd, ExtremeSolver::gauss_seidel_pbd});
}

TEST(SolverExtremes, LongTimeStepConvergesToNewtonsField) {
  expect_converged_or_warned({1e5, 0.3, 10.0, 0.0},
                             {ExtremeSolver::local_global, ExtremeSolver::jacobi_chebyshev});
}

TEST(SolverExtremes, EndPushedTowardsTheHeldEndConvergesOrWarns) {
  expect_converged_or_warned({1e5, 0.3, 0.0, 90.0}, {ExtremeSolver::local_global, ExtremeSolver::newton});
}
