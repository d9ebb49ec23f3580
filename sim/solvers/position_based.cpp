#include "sim/solvers/position_based.hpp"

namespace phantasm::sim_detail {
namespace {

class PositionBasedFrameSolver : public PreparedSolver {
public:
  explicit PositionBasedFrameSolver(PositionBasedVariant variant) : m_variant(variant) {}
  SolveReport solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                    const StopCriteria& stop) override {
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      if (!model.fixed[static_cast<std::size_t>(v)]) p.row(v) = inertia.target_m.row(v);
    return position_based_solve(m_variant, model, inertia, p, stop);
  }

private:
  PositionBasedVariant m_variant;
};

} // namespace

std::unique_ptr<PreparedSolver> make_position_based_solver(PositionBasedVariant variant) {
  return std::make_unique<PositionBasedFrameSolver>(variant);
}

} // namespace phantasm::sim_detail
