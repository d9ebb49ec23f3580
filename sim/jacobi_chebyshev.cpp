// The Jacobi + Chebyshev variant of the local/global solver (Wang 2015): the global solve
// replaced by one Jacobi sweep per iteration, accelerated by Chebyshev's semi-iterative method.
#include "sim/local_global.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "sim/local_global_impl.hpp"
#include "sim/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

namespace phantasm {

double LocalGlobalSolver::jacobi_spectral_radius() {
  const Eigen::Index nf = m->K_free.rows();
  if (nf == 0) return 0.0;
  const Eigen::VectorXd inverse_diagonal = m->K_free.diagonal().cwiseInverse();
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(nf, 1.0, 2.0); // deterministic start
  v.normalize();
  double rho = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::VectorXd Kv = m->K_free.selfadjointView<Eigen::Lower>() * v;
    Eigen::VectorXd w = v - inverse_diagonal.cwiseProduct(Kv);
    const double norm = w.norm();
    if (norm == 0.0) return 0.0;
    rho = norm; // |J v| with |v| = 1 converges to the spectral radius for the dominant mode
    v = w / norm;
  }
  return std::min(rho, 1.0 - 1e-12);
}

SolveReport LocalGlobalSolver::solve_jacobi_chebyshev(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target,
                                                      const StopCriteria& stop, bool record_energies,
                                                      const IterationObserver& observer,
                                                      double under_relaxation, double rho_scale) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  };
  SolveReport report;
  report.solver = "jacobi_chebyshev";
  const double rho = rho_scale * jacobi_spectral_radius();
  double energy = m->begin_solve(p, target, report, record_energies, observer);
  auto start = Clock::now();
  const auto nf = static_cast<Eigen::Index>(m->free_vertex.size());
  Eigen::MatrixX3d x = m->free_positions(p);
  Eigen::MatrixX3d x_previous = x, best = x;
  double best_energy = energy;
  Eigen::MatrixX3d inverse_diagonal = m->K_free.diagonal().cwiseInverse().replicate(1, 3);
  double omega = 1.0;
  int step = 0; // iterations since the acceleration (re)started
  std::optional<ResidualTest> test;
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    throw_if_cancelled(); // an iteration takes milliseconds to a second: SIGINT stops here
    start = Clock::now();
    const bool contacts_changed = m->contacts->update_factor(*m->factor) > 0;
    m->gather_rhs(target);
    report.local_seconds += seconds_since(start);
    start = Clock::now();
    if (contacts_changed) inverse_diagonal = m->matrix_diagonal().cwiseInverse();
    const Eigen::MatrixX3d Kx = m->apply_matrix(x);
    // The equilibrium residual at x: the residual test before every step (and after the last,
    // in finish_report).
    const double residual = nf > 0 ? (Kx - m->rhs).rowwise().norm().maxCoeff() : 0.0;
    if (!test) test.emplace(stop, residual);
    if (progress_detail_due()) progress_detail(solver_detail(iteration, residual));
    if (test->passes(residual)) {
      report.global_seconds += seconds_since(start);
      report.stopped_by = "residual";
      break;
    }
    const Eigen::MatrixX3d jacobi = x + inverse_diagonal.cwiseProduct(m->rhs - Kx);
    ++step;
    omega = step == 1 ? 1.0 : step == 2 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
    const Eigen::MatrixX3d next = omega * (under_relaxation * (jacobi - x) + x - x_previous) + x_previous;
    report.global_seconds += seconds_since(start);
    start = Clock::now();
    m->set_free_positions(next, p);
    energy = m->local_step(p, target);
    x_previous = x;
    x = next;
    if (std::isfinite(energy) && m->contacts->pending()) {
      // New or released contacts: the energy is another function from here; restart the
      // acceleration at this point rather than returning to one with the old contacts.
      best = x;
      best_energy = energy;
      x_previous = x;
      step = 0;
    } else if (!std::isfinite(energy) || energy > best_energy) {
      // Restart the acceleration from the best point so far.
      x = best;
      x_previous = best;
      step = 0;
      m->set_free_positions(best, p);
      energy = m->local_step(p, target);
    } else {
      best = x;
      best_energy = energy;
    }
    report.local_seconds += seconds_since(start);
    report.iterations = iteration;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(report.local_seconds + report.global_seconds);
    }
    if (observer) observer(iteration, p, energy);
    // The step criteria stop nothing the residual test does not (a small step is not a small
    // distance to equilibrium): the test at the next iteration's start decides.
  }
  report.final_energy_J = energy;
  m->finish_report(x, target, report);
  if (!test) test.emplace(stop, report.residual_N);
  finish_solve(m->model, StepInertia{m->alpha, target}, p, stop, *test, true, report);
  return report;
}

} // namespace phantasm
