#pragma once

#include "sim/elastic_model.hpp"
#include "sim/solve_report.hpp"

#include <Eigen/Core>

#include <memory>

namespace phantasm {

/// The local/global solver of projective dynamics on an ElasticModel (METHOD.md section 2).
/// The global matrix a M + sum w A^T A over the free vertices is factored once (CHOLMOD,
/// supernodal) when the solver is made; each iteration projects every tet in parallel (OpenMP,
/// signed SVD with warm-started rotations, no allocation), gathers the right-hand side per
/// vertex, and solves the three coordinates in one pass over the factor. Fixed vertices stay
/// where they are in the positions passed to solve().
class LocalGlobalSolver {
public:
  /// @param inertia_weight 1/h^2 of the steps to solve, or 0 for quasi-static solves (then the
  ///        model needs fixed vertices or point constraints, or the matrix is singular)
  /// @param threads OpenMP threads of the local step (0: all)
  /// @param anderson_history iterations Anderson acceleration remembers (0: plain local/global).
  ///        Accelerated points are kept only when they lower the energy (Peng et al. 2018), so
  ///        the energy never increases either way.
  /// @throws std::runtime_error when the matrix cannot be factored (nothing holds the model)
  LocalGlobalSolver(const ElasticModel& model, double inertia_weight, int threads = 0,
                    int anderson_history = 5);
  ~LocalGlobalSolver();
  LocalGlobalSolver(const LocalGlobalSolver&) = delete;
  LocalGlobalSolver& operator=(const LocalGlobalSolver&) = delete;

  /// Iterates from p (metres, one row per vertex) until a stop criterion holds; p is replaced
  /// by the result. `inertial_target` is s (ignored for quasi-static). With record_energies, the
  /// report lists E(p_k) for every iteration (E costs nothing extra: the local step computes it).
  SolveReport solve(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target, const StopCriteria& stop,
                    bool record_energies = false, const IterationObserver& observer = {});

  /// One local step at p: the energy E(p), and (into the solver's buffers) the projections.
  double energy(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target);

private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

} // namespace phantasm
