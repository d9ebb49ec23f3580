#include "sim/newton.hpp"
#include "sim/prepared_solver.hpp"

namespace phantasm::sim_detail {
namespace {

/// Newton's method, its Hessian formed and factored in every iteration: nothing to prepare.
class NewtonFrameSolver : public PreparedSolver {
public:
  NewtonFrameSolver(const ElasticModel&, double, const SolverSettings&) {}
  SolveReport solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                    const StopCriteria& stop) override {
    return newton_solve(model, inertia, p, stop);
  }
};

} // namespace

const SolverEntry& newton_solver_entry() {
  static const SolverEntry entry{SolverMethod::newton, &make_prepared_solver<NewtonFrameSolver>};
  return entry;
}

} // namespace phantasm::sim_detail
