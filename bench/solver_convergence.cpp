// Iterations and solver time to reach relative errors 1e-1, 1e-2, 1e-3 on one frame of the
// twisting bar, for each solver, with both definitions of docs/method.md section 6:
//   energy    e_k = (E(p_k) - E*) / (E(p_0) - E*)
//   position  r_k = |p_k - p*| / |p_0 - p*|
// p_0 = s (the inertial target with the prescribed ends), p* from Newton run to a gradient
// below 1e-9 N. Prints a Markdown table (docs/performance.md's); with a second argument, also writes
// every iteration (solver, iteration, seconds, energy error, position error) as CSV there for
// scripts/accuracy_plots.py. With "quick" as a third argument each iterative solver stops after a
// tenth of its iterations (the plots' shape near the start, for the test of the plotting command).
// Usage: solver_convergence [threads] [traces.csv] [quick]

#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/twisting_bar.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct Reached {
  int iteration = -1;
  double seconds = 0.0;
};

struct Row {
  std::string solver;
  Reached energy[3], position[3];
};

const double k_levels[3] = {1e-1, 1e-2, 1e-3};

std::string cell(const Reached& r) {
  if (r.iteration < 0) return "not reached";
  char text[64];
  std::snprintf(text, sizeof text, "%d it, %.1f ms", r.iteration, 1e3 * r.seconds);
  return text;
}

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm;
  const int threads = argc > 1 ? std::atoi(argv[1]) : 2;
  const int iteration_divisor = argc > 3 && std::strcmp(argv[3], "quick") == 0 ? 10 : 1;
  const TwistingBarStep bar = twisting_bar_step({});
  Eigen::MatrixX3d reference = bar.start_m;
  StopCriteria tight;
  tight.max_iterations = 60;
  tight.gradient_norm_N = 1e-9;
  const SolveReport newton_reference = newton_solve(bar.model, bar.inertia, reference, tight);
  const double E_star = newton_reference.final_energy_J;
  const double E_0 = model_energy(bar.model, bar.inertia, bar.start_m);
  const double r_0 = (bar.start_m - reference).norm();
  std::fprintf(stderr, "reference: Newton %d iterations, residual %.3g N, E* = %.10g J\n",
               newton_reference.iterations, newton_reference.residual_N, E_star);

  std::vector<Row> rows;
  std::FILE* traces = argc > 2 ? std::fopen(argv[2], "w") : nullptr;
  if (argc > 2 && !traces) {
    std::fprintf(stderr, "solver_convergence: cannot write %s\n", argv[2]);
    return 1;
  }
  if (traces) std::fprintf(traces, "solver,iteration,seconds,energy_error,position_error\n");
  auto track = [&](Row& row, const SolveReport& report, const std::vector<double>& position_errors) {
    for (std::size_t k = 0; k < report.energies_J.size(); ++k) {
      const double e = (report.energies_J[k] - E_star) / (E_0 - E_star);
      if (traces) {
        std::fprintf(traces, "\"%s\",%zu,%.6g,%.6g,%.6g\n", row.solver.c_str(), k, report.seconds[k], e,
                     position_errors[k]);
      }
      for (int level = 0; level < 3; ++level) {
        if (row.energy[level].iteration < 0 && e <= k_levels[level])
          row.energy[level] = {static_cast<int>(k), report.seconds[k]};
        if (row.position[level].iteration < 0 && position_errors[k] <= k_levels[level])
          row.position[level] = {static_cast<int>(k), report.seconds[k]};
      }
    }
  };
  {
    Row row{"local/global (" + std::to_string(threads) + " threads)", {}, {}};
    LocalGlobalSolver solver(bar.model, bar.inertia.weight, threads);
    Eigen::MatrixX3d p = bar.start_m;
    StopCriteria stop;
    stop.max_iterations = 5000 / iteration_divisor;
    stop.relative_energy_decrease = 0.0;
    stop.position_change_m = 0.0;
    std::vector<double> position_errors;
    const SolveReport report =
        solver.solve(p, bar.inertia.target_m, stop, true, [&](int, const Eigen::MatrixX3d& q, double) {
          position_errors.push_back((q - reference).norm() / r_0);
        });
    track(row, report, position_errors);
    rows.push_back(row);
  }
  {
    Row row{"Jacobi + Chebyshev (" + std::to_string(threads) + " threads)", {}, {}};
    LocalGlobalSolver solver(bar.model, bar.inertia.weight, threads);
    Eigen::MatrixX3d p = bar.start_m;
    StopCriteria stop;
    stop.max_iterations = 3000 / iteration_divisor;
    stop.relative_energy_decrease = 0.0;
    stop.position_change_m = 0.0;
    std::vector<double> position_errors;
    const SolveReport report = solver.solve_jacobi_chebyshev(
        p, bar.inertia.target_m, stop, true, [&](int, const Eigen::MatrixX3d& q, double) {
          position_errors.push_back((q - reference).norm() / r_0);
        });
    std::fprintf(stderr, "Jacobi + Chebyshev: rho %.6f, %d iterations, energy error %.3g\n",
                 solver.jacobi_spectral_radius(), report.iterations,
                 (report.final_energy_J - E_star) / (E_0 - E_star));
    track(row, report, position_errors);
    rows.push_back(row);
  }
  {
    Row row{"XPBD (1 thread, Gauss-Seidel sweeps)", {}, {}};
    Eigen::MatrixX3d p = bar.start_m;
    StopCriteria stop;
    stop.max_iterations = 1500 / iteration_divisor;
    stop.relative_energy_decrease = 0.0;
    stop.position_change_m = 0.0;
    std::vector<double> position_errors;
    const SolveReport report = position_based_solve(PositionBasedVariant::xpbd, bar.model, bar.inertia, p,
                                                    stop, true, [&](int, const Eigen::MatrixX3d& q, double) {
                                                      position_errors.push_back((q - reference).norm() / r_0);
                                                    });
    std::fprintf(stderr, "XPBD: %d sweeps, energy error %.3g, position error %.3g\n", report.iterations,
                 (report.final_energy_J - E_star) / (E_0 - E_star), position_errors.back());
    track(row, report, position_errors);
    rows.push_back(row);
  }
  {
    Row row{"Newton (PSD-projected, CHOLMOD, Armijo)", {}, {}};
    Eigen::MatrixX3d p = bar.start_m;
    StopCriteria stop;
    stop.max_iterations = 20;
    stop.gradient_norm_N = 1e-9;
    std::vector<double> position_errors;
    const SolveReport report =
        newton_solve(bar.model, bar.inertia, p, stop, true, [&](int, const Eigen::MatrixX3d& q, double) {
          position_errors.push_back((q - reference).norm() / r_0);
        });
    track(row, report, position_errors);
    rows.push_back(row);
  }
  if (traces) std::fclose(traces);
  std::printf("| solver | energy 1e-1 | energy 1e-2 | energy 1e-3 | position 1e-1 | position 1e-2 | position "
              "1e-3 |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Row& row : rows) {
    std::printf("| %s | %s | %s | %s | %s | %s | %s |\n", row.solver.c_str(), cell(row.energy[0]).c_str(),
                cell(row.energy[1]).c_str(), cell(row.energy[2]).c_str(), cell(row.position[0]).c_str(),
                cell(row.position[1]).c_str(), cell(row.position[2]).c_str());
  }
  return 0;
}
