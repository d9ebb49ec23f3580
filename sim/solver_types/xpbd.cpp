#include "sim/solver_type.hpp"

namespace phantasm {

const SolverType& xpbd_solver_type() {
  static const SolverType type{
      SolverMethod::xpbd, "xpbd",
      "extended position-based dynamics: compliant constraints stepped in time (dynamic only)",
      /*steps_in_time=*/true,
      // Per shell triangle per frame and load step: local/global's rate (not measured on its own).
      /*seconds_per_shell_triangle_step=*/80e-6};
  return type;
}

} // namespace phantasm
