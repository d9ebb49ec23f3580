#include "sim/newton.hpp"
#include "sim/prepared_solver.hpp"

namespace phantasm::sim_detail {
namespace {

/// Newton's method, its Hessian formed and factored in every iteration: nothing to prepare.
class NewtonFrameSolver : public PreparedSolver {
public:
  SolveReport solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                    const StopCriteria& stop) override {
    return newton_solve(model, inertia, p, stop);
  }
};

} // namespace

const SolverEntry& newton_solver_entry() {
  static const SolverEntry entry{
      SolverMethod::newton,
      [](const ElasticModel&, double, const SolverSettings&) -> std::unique_ptr<PreparedSolver> {
        return std::make_unique<NewtonFrameSolver>();
      }};
  return entry;
}

} // namespace phantasm::sim_detail
