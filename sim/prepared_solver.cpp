#include "sim/prepared_solver.hpp"

#include "core/registry.hpp"

namespace phantasm::sim_detail {

// The entry points, one per file of sim/solvers/.
const SolverEntry& local_global_solver_entry();
const SolverEntry& newton_solver_entry();
const SolverEntry& gauss_seidel_pbd_solver_entry();
const SolverEntry& jacobi_chebyshev_solver_entry();
const SolverEntry& xpbd_solver_entry();

namespace {

const Registry<SolverEntry, SolverMethod>& solver_entry_registry() {
  // The registrations, beside those of solver_types() (docs/architecture.md, Adding a variant).
  static const Registry<SolverEntry, SolverMethod> entries(
      "solver entry", &SolverEntry::method,
      {&local_global_solver_entry(), &newton_solver_entry(), &gauss_seidel_pbd_solver_entry(),
       &jacobi_chebyshev_solver_entry(), &xpbd_solver_entry()});
  return entries;
}

} // namespace

const std::vector<const SolverEntry*>& solver_entries() {
  return solver_entry_registry().members();
}

const SolverEntry& solver_entry(SolverMethod method) {
  return solver_entry_registry().at(method);
}

} // namespace phantasm::sim_detail
