#include "sim/solvers/position_based.hpp"

namespace phantasm::sim_detail {

const SolverEntry& gauss_seidel_pbd_solver_entry() {
  static const SolverEntry entry{SolverMethod::gauss_seidel_pbd,
                                 [](const ElasticModel&, double, const SolverSettings&) {
                                   return make_position_based_solver(PositionBasedVariant::gauss_seidel_pbd);
                                 }};
  return entry;
}

} // namespace phantasm::sim_detail
