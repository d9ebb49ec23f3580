// The entry points of the solvers (sim/solvers/NAME.cpp), keyed by the method of their member of
// the solver registry (sim/solver_type.hpp): what the frame loop (sim/load_schedule.cpp) makes
// once per deformation and calls once per frame or load step. Internal to sim.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/sim_settings.hpp"
#include "sim/solve_report.hpp"

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace phantasm::sim_detail {

/// A solver prepared for the solves of one deformation (local/global factors its matrix once).
class PreparedSolver {
public:
  virtual ~PreparedSolver() = default;
  /// One solve of a frame or load step from p (metres, one row per model vertex; replaced by its
  /// result), toward the step's inertial target (quasi-static: inertia.weight 0).
  virtual SolveReport solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                            const StopCriteria& stop) = 0;
};

/// A solver's entry point.
struct SolverEntry {
  SolverMethod method;
  /// Prepares the solver for a model.
  /// @param inertia_weight 1/h^2 of dynamic steps, 0 for quasi-static solves
  /// @throws std::runtime_error when the model cannot be solved as set (nothing holds it)
  std::unique_ptr<PreparedSolver> (*make)(const ElasticModel& model, double inertia_weight,
                                          const SolverSettings& settings) = nullptr;
};

/// The `make` of an entry whose solver is constructed from (model, inertia_weight, settings).
template <class Solver>
std::unique_ptr<PreparedSolver> make_prepared_solver(const ElasticModel& model, double inertia_weight,
                                                     const SolverSettings& settings) {
  return std::make_unique<Solver>(model, inertia_weight, settings);
}

/// Every registered entry point, beside the members of solver_types().
const std::vector<const SolverEntry*>& solver_entries();

/// The entry point of a method (every method has one).
const SolverEntry& solver_entry(SolverMethod method);

} // namespace phantasm::sim_detail
