#include "sim/local_global.hpp"
#include "sim/prepared_solver.hpp"

namespace phantasm::sim_detail {
namespace {

/// Local/global iterations on the matrix factored once for the deformation.
class LocalGlobalFrameSolver : public PreparedSolver {
public:
  LocalGlobalFrameSolver(const ElasticModel& model, double inertia_weight, const SolverSettings& settings)
      : m_solver(model, inertia_weight, settings.threads) {}
  SolveReport solve(const ElasticModel&, const StepInertia& inertia, Eigen::MatrixX3d& p,
                    const StopCriteria& stop) override {
    return m_solver.solve(p, inertia.target_m, stop);
  }

private:
  LocalGlobalSolver m_solver;
};

} // namespace

const SolverEntry& local_global_solver_entry() {
  static const SolverEntry entry{SolverMethod::local_global, &make_prepared_solver<LocalGlobalFrameSolver>};
  return entry;
}

} // namespace phantasm::sim_detail
