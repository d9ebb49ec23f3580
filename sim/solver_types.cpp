#include "sim/solver_type.hpp"

#include "core/registry.hpp"

namespace phantasm {

// The members, one per file of sim/solver_types/.
const SolverType& local_global_solver_type();
const SolverType& newton_solver_type();
const SolverType& gauss_seidel_pbd_solver_type();
const SolverType& jacobi_chebyshev_solver_type();
const SolverType& xpbd_solver_type();

namespace {

const Registry<SolverType, SolverMethod>& solver_registry() {
  // The registrations: a new solver adds its line here and its declaration above, and its entry
  // point in sim/prepared_solver.cpp (docs/architecture.md, Adding a variant).
  static const Registry<SolverType, SolverMethod> types(
      "solver", &SolverType::method,
      {&local_global_solver_type(), &newton_solver_type(), &gauss_seidel_pbd_solver_type(),
       &jacobi_chebyshev_solver_type(), &xpbd_solver_type()});
  return types;
}

} // namespace

const std::vector<const SolverType*>& solver_types() {
  return solver_registry().members();
}

const SolverType& solver_type(SolverMethod method) {
  return solver_registry().at(method);
}

const SolverType* find_solver_type(const std::string& name) {
  return solver_registry().find(name);
}

std::vector<std::string> solver_type_names() {
  return solver_registry().names();
}

std::string static_solver_names() {
  return solver_registry().names_text([](const SolverType& type) { return !type.steps_in_time; });
}

const char* to_string(SolverMethod method) {
  return solver_type(method).name;
}

} // namespace phantasm
