// The Newton solver on the same objective as the local/global solver, with projected per-tet
// Hessians and line search: the reference the other solvers are measured against.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/solve_report.hpp"

namespace phantasm {

/// The Newton reference on the same objective (docs/method.md section 5): per-tet Hessians from the
/// closed-form eigensystem of the isotropic constraint energies, projected to positive
/// semi-definite; sparse Cholesky (CHOLMOD) every iteration; Armijo backtracking. Fixed vertices
/// stay where they are in p. Stops on the gradient norm (stop.gradient_norm_N when set, else the
/// residual test of `stop` and, when asked, its distance test on the Newton step), the energy
/// decrease when the residual test passes too (not with the distance test), a step that can no
/// longer lower the energy, or the iteration limit.
SolveReport newton_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                         const StopCriteria& stop, bool record_energies = false,
                         const IterationObserver& observer = {});

/// The Newton step at p (the PSD-projected Hessian): the largest free vertex's step (m), an
/// estimate of its distance to the equilibrium (exact to second order near a stable one).
double newton_step_length(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p);

/// The end of a solve that stopped at p (report's residual_N at p): judges the residual test
/// and, when `stop` asks for it, the distance test (StopCriteria::relative_distance). With
/// `newton_steps`, a result whose residual passes and whose distance does not is finished by
/// Newton iterations (at most 200; p, the residual, energy and iterations follow); without, the
/// distance is only measured. Either way the report says how far the result is.
void finish_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                  const StopCriteria& stop, const ResidualTest& test, bool newton_steps, SolveReport& report);

} // namespace phantasm
