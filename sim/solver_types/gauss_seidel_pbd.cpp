#include "sim/solver_type.hpp"

namespace phantasm {

const SolverType& gauss_seidel_pbd_solver_type() {
  static const SolverType type{
      SolverMethod::gauss_seidel_pbd, "gauss_seidel_pbd",
      "Gauss-Seidel position-based dynamics: each constraint projected in turn, hard constraints (dynamic "
      "only)",
      /*steps_in_time=*/true,
      // Per shell triangle per frame and load step: local/global's rate (not measured on its own).
      /*seconds_per_shell_triangle_step=*/80e-6};
  return type;
}

} // namespace phantasm
