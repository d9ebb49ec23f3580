// LocalGlobalSolver, the projective-dynamics solver of the deformation stage: a prefactored
// global matrix, parallel per-tet projections, contacts by rank-one updates of the factor.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/solve_report.hpp"

#include <Eigen/Core>

#include <memory>

namespace phantasm {

/// The local/global solver of projective dynamics on an ElasticModel (docs/method.md section 2).
/// The global matrix a M + sum w A^T A over the free vertices is factored once (CHOLMOD,
/// simplicial LDL^T) when the solver is made; each iteration projects every tet in parallel
/// (OpenMP, signed SVD with warm-started rotations, no allocation), finds the vertices inside
/// obstacles, gathers the right-hand side per vertex, brings the factor up to date with the
/// contacts by rank-one updates/downdates, and solves the three coordinates in one pass over the
/// factor, accelerated by Anderson's method. A solve that has not converged after 100 such
/// iterations (and has no contacts) goes on as L-BFGS on the same energy with the factor as its
/// initial Hessian (Liu, Bouaziz and Kavan 2017), which converges where the plain iteration
/// crawls (nu near 1/2: docs/deformation.md). Fixed vertices stay where they are in the
/// positions passed to solve().
class LocalGlobalSolver {
public:
  /// @param inertia_weight 1/h^2 of the steps to solve, or 0 for quasi-static solves (then the
  ///        model needs fixed vertices or point constraints, or the matrix is singular)
  /// @param threads OpenMP threads of the local step (0: all)
  /// @param anderson_history iterations Anderson acceleration remembers (0: plain local/global).
  ///        Accelerated points are kept only when they lower the energy (Peng et al. 2018), so
  ///        the energy never increases either way.
  /// @param history pairs the L-BFGS phase of solve() remembers (0: no L-BFGS phase). Its
  ///        steps must lower the energy enough (Armijo), else the plain step is taken.
  /// @throws std::runtime_error when the matrix cannot be factored (nothing holds the model)
  LocalGlobalSolver(const ElasticModel& model, double inertia_weight, int threads = 0,
                    int anderson_history = 5, int history = 30);
  ~LocalGlobalSolver();
  LocalGlobalSolver(const LocalGlobalSolver&) = delete;
  LocalGlobalSolver& operator=(const LocalGlobalSolver&) = delete;

  /// Iterates from p (metres, one row per vertex) until the residual test of `stop` passes (its
  /// residual is K x - b(x), the energy's gradient, checked before every step at the cost of one
  /// product with K), a step moves nothing, or the iteration limit; p is replaced
  /// by the result. `inertial_target` is s (ignored for quasi-static). With record_energies, the
  /// report lists E(p_k) for every iteration (E costs nothing extra: the local step computes it).
  SolveReport solve(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target, const StopCriteria& stop,
                    bool record_energies = false, const IterationObserver& observer = {});

  /// The same iteration with the global solve replaced by one Jacobi sweep over the global
  /// matrix, accelerated by Chebyshev's semi-iterative method (Wang 2015: x_k+1 = omega_k+1
  /// (gamma (x^ - x_k) + x_k - x_k-1) + x_k-1, omega_1 = 1, omega_2 = 2 / (2 - rho^2),
  /// omega_k+1 = 4 / (4 - rho^2 omega_k)), with rho the spectral radius of the Jacobi iteration
  /// matrix estimated by power iteration (times `rho_scale`) and gamma = `under_relaxation`.
  /// When an iteration raises the energy, the acceleration restarts from the better point.
  /// Stops as solve() does, on the residual test or the iteration limit.
  SolveReport solve_jacobi_chebyshev(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target,
                                     const StopCriteria& stop, bool record_energies = false,
                                     const IterationObserver& observer = {}, double under_relaxation = 0.9,
                                     double rho_scale = 0.999);
  /// The spectral radius of the Jacobi iteration matrix I - D^-1 K of the global system.
  double jacobi_spectral_radius();

  /// One local step at p: the energy E(p), and (into the solver's buffers) the projections.
  double energy(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target);

private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

} // namespace phantasm
