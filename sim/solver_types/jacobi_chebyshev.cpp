#include "sim/solver_type.hpp"

namespace phantasm {

const SolverType& jacobi_chebyshev_solver_type() {
  static const SolverType type{
      SolverMethod::jacobi_chebyshev, "jacobi_chebyshev",
      "the local/global step with one Chebyshev-accelerated Jacobi sweep for the global solve",
      /*steps_in_time=*/false,
      // Per shell triangle per frame and load step: local/global's rate (not measured on its own).
      /*seconds_per_shell_triangle_step=*/80e-6};
  return type;
}

} // namespace phantasm
