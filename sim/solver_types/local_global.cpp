#include "sim/solver_type.hpp"

namespace phantasm {

const SolverType& local_global_solver_type() {
  static const SolverType type{
      SolverMethod::local_global,
      "local_global",
      "local/global iterations on a matrix factored once, Anderson-accelerated, then L-BFGS (the default)",
      /*steps_in_time=*/false,
      // Per shell triangle per frame and load step: a shell's solve takes more iterations than a solid's
      // (cloth.yaml's swing: hundreds per frame).
      /*seconds_per_shell_triangle_step=*/80e-6,
      /*literature=*/
      {"Projective Dynamics", "S. Bouaziz, S. Martin, T. Liu, L. Kavan, M. Pauly, Projective Dynamics: "
                              "Fusing Constraint Projections for Fast Simulation, ACM Transactions on "
                              "Graphics 33(4), 2014."}};
  return type;
}

} // namespace phantasm
