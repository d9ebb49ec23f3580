// Position-based solvers (XPBD and Gauss-Seidel PBD) of one dynamic step on an ElasticModel's
// constraints: deterministic sweeps, compared with the local/global solver.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/solve_report.hpp"

namespace phantasm {

/// Position-based solvers of one dynamic step (docs/method.md section 4) on the constraints of an
/// ElasticModel: per tet its strain and volume constraints and per surface element its
/// constraint as C = |F - P(F)| (the distance of F to its set, so w/2 C^2 is the model's energy
/// term), per point constraint C = |b . x - t|, per free vertex and obstacle it is inside C = its depth. One
/// iteration is one Gauss-Seidel sweep over them in a fixed order (deterministic, one thread), starting from
/// p.
enum class PositionBasedVariant {
  /// XPBD (Macklin et al. 2016): compliance alpha = 1/w, dlambda = (-C - alpha~ lambda) /
  /// (sum_k |grad_k C|^2 / m_k + alpha~), alpha~ = alpha / h^2. Its fixed point is the minimizer
  /// of the step's energy, the one local/global and Newton reach.
  xpbd,
  /// Gauss-Seidel PBD: every constraint projected in turn, dx_k = -C grad_k C / m_k /
  /// sum_j |grad_j C|^2 / m_j, whatever its stiffness (hard constraints). It converges to a
  /// point of every set when they intersect, not to the minimizer of the energy.
  gauss_seidel_pbd,
};

/// Iterates until the residual test of `stop` passes or the iteration limit (the step criteria
/// stop nothing the residual test does not: a small sweep is not a small distance to
/// equilibrium); p is replaced by the result. E and the gradient are evaluated after every
/// sweep for the stop test and the report but, like an observer, not counted in the solver's time. External
/// forces act through the inertial target (s + h^2 M^-1 f).
/// @throws std::invalid_argument for a quasi-static step (inertia.weight 0): position-based
///         methods step in time
SolveReport position_based_solve(PositionBasedVariant variant, const ElasticModel& model,
                                 const StepInertia& inertia, Eigen::MatrixX3d& p, const StopCriteria& stop,
                                 bool record_energies = false, const IterationObserver& observer = {});

} // namespace phantasm
