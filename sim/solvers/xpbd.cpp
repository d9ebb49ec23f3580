#include "sim/solvers/position_based.hpp"

namespace phantasm::sim_detail {

const SolverEntry& xpbd_solver_entry() {
  static const SolverEntry entry{SolverMethod::xpbd, [](const ElasticModel&, double, const SolverSettings&) {
                                   return make_position_based_solver(PositionBasedVariant::xpbd);
                                 }};
  return entry;
}

} // namespace phantasm::sim_detail
