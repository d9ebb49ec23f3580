// The registry of deformation solvers: one member per solver (sim/solver_types/NAME.cpp), each
// the one place that knows its name in the scene, its help, whether it steps in time (then a
// quasi-static scene is refused), its term of the cost estimate and the literature of its method
// (which the report's methods paragraph cites). The standard library only,
// so the scene and the cost estimate read the members without the solvers; how a member solves
// lives beside it in sim/solvers/NAME.cpp (sim/prepared_solver.hpp). Adding a solver:
// docs/architecture.md, "Adding a variant".
#pragma once

#include "sim/sim_settings.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// The method a solver implements as the literature names it, and where it was published.
struct SolverLiterature {
  const char* method = nullptr;    ///< "Projective Dynamics" ("... by the local_global solver of ...")
  const char* reference = nullptr; ///< authors, title, journal, volume, year (plain text), as cited
};

/// One solver of the registry.
struct SolverType {
  SolverMethod method;
  const char* name;        ///< the scene's deformation.solver.method
  const char* description; ///< one line for help and the docs' table
  /// It steps in time (position-based dynamics): a quasi-static scene is refused.
  bool steps_in_time = false;
  /// The cost estimate's processor time per shell triangle per frame and load step, s.
  double seconds_per_shell_triangle_step = 0.0;
  /// Its method in the literature, cited by the report's methods paragraph; none (nulls) for a
  /// method of the project's own or of textbooks.
  SolverLiterature literature = {};
};

/// Every registered solver, in the docs' order.
const std::vector<const SolverType*>& solver_types();

/// The member of a method (every method has one).
const SolverType& solver_type(SolverMethod method);

/// The member named `name`, or null.
const SolverType* find_solver_type(const std::string& name);

/// The registered names, in order.
std::vector<std::string> solver_type_names();

/// The names of the solvers that reach a static equilibrium (do not step in time), as a
/// reader's list: "local_global, newton or jacobi_chebyshev".
std::string static_solver_names();

} // namespace phantasm
