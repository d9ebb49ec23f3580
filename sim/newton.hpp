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
/// residual test of `stop`), the energy decrease when the residual test passes too, a step
/// that can no longer lower the energy, or the iteration limit.
SolveReport newton_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                         const StopCriteria& stop, bool record_energies = false,
                         const IterationObserver& observer = {});

} // namespace phantasm
