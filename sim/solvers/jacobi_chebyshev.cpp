#include "sim/local_global.hpp"
#include "sim/prepared_solver.hpp"

namespace phantasm::sim_detail {
namespace {

/// The local/global step with Chebyshev-accelerated Jacobi sweeps over the matrix of the
/// deformation.
class JacobiChebyshevFrameSolver : public PreparedSolver {
public:
  JacobiChebyshevFrameSolver(const ElasticModel& model, double inertia_weight, const SolverSettings& settings)
      : m_solver(model, inertia_weight, settings.threads) {}
  SolveReport solve(const ElasticModel&, const StepInertia& inertia, Eigen::MatrixX3d& p,
                    const StopCriteria& stop) override {
    return m_solver.solve_jacobi_chebyshev(p, inertia.target_m, stop);
  }

private:
  LocalGlobalSolver m_solver;
};

} // namespace

const SolverEntry& jacobi_chebyshev_solver_entry() {
  static const SolverEntry entry{SolverMethod::jacobi_chebyshev,
                                 &make_prepared_solver<JacobiChebyshevFrameSolver>};
  return entry;
}

} // namespace phantasm::sim_detail
