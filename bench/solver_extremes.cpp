// The extremes table of docs/deformation.md (#16): the cantilever of tests/sim at Young's moduli
// from 1 Pa to 1 GPa, Poisson ratios from 0 to 0.4999, time steps from 1e-6 to 10 s and loads
// that invert it, for every solver with the scene defaults, each row against Newton's converged
// answer (bench/solver_extremes.hpp). Prints the table as Markdown; exit status 1 when a row is a
// silent wrong answer (converged, nothing inverted, and off the oracle).
// Usage: solver_extremes [first_case [last_case [solver]]] (cases 0-based, inclusive; default
// all; solver: one of local_global, jacobi_chebyshev, newton, xpbd, gauss_seidel_pbd)
//        solver_extremes locking [CELLS...]: the volume-locking rows, Newton's tip (relative
//        residual 1e-7) on the bar with CELLS cells across (default 4 8) at nu 0.45, 0.49, 0.499,
//        per tet, on tet groups and on tet groups and tets

#include "bench/solver_extremes.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

using namespace phantasm;
using namespace phantasm::bench;

std::string number(double x, int digits = 3) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, x);
  return text;
}

std::string describe(const ExtremeCase& c) {
  std::string s = "E " + number(c.youngs_modulus_Pa) + " Pa, nu " + number(c.poisson_ratio, 4) + ", ";
  s += c.time_step_s > 0.0 ? "h " + number(c.time_step_s) + " s" : "static";
  if (c.push_mm > 0.0) s += ", end pushed " + number(c.push_mm) + " mm";
  if (c.twist_deg != 0.0) s += ", end twisted " + number(c.twist_deg) + " degrees";
  return s;
}

/// The volume-locking rows: Newton's tip per bulk term and Poisson ratio on bars of `cells`.
int locking_rows(std::FILE* table, const std::vector<int>& cells) {
  std::fprintf(table, "| bulk term | cells | nu 0.45 | nu 0.49 | nu 0.499 | 0.499 vs 0.45 | time |\n"
                      "|---|---|---|---|---|---|---|\n");
  for (int n : cells)
    for (VolumeFormulation v :
         {VolumeFormulation::tet, VolumeFormulation::tet_group, VolumeFormulation::tet_group_and_tet}) {
      const auto start = std::chrono::steady_clock::now();
      std::vector<double> tips;
      for (double nu : {0.45, 0.49, 0.499}) {
        ExtremeCase c; // 100 kPa, quasi-static
        c.poisson_ratio = nu;
        c.volume = v;
        c.cells_across = n;
        const ExtremeCantilever k = extreme_cantilever(c);
        const ExtremeOracle oracle = extreme_oracle(k);
        if (!oracle_converged(oracle))
          std::fprintf(stderr, "%d cells, nu %g: Newton did not converge\n", n, nu);
        tips.push_back(tip_deflection_mm(k, oracle.p));
      }
      std::fprintf(table, "| %s | %d x %d x %d | %.2f mm | %.2f mm | %.2f mm | %+.1f %% | %.0f s |\n",
                   to_string(v), n, n, 5 * n, tips[0], tips[1], tips[2], 100.0 * (tips[2] / tips[0] - 1.0),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      std::fflush(table);
    }
  return 0;
}

} // namespace

int main(int argc, char** argv) {
  // The table goes to stdout; CHOLMOD's warnings (a singular Hessian, which Newton shifts) to stderr.
  std::FILE* table = fdopen(dup(1), "w");
  dup2(2, 1);
  if (argc > 1 && std::string(argv[1]) == "locking") {
    std::vector<int> cells;
    for (int a = 2; a < argc; ++a)
      cells.push_back(std::atoi(argv[a]));
    return locking_rows(table, cells.empty() ? std::vector<int>{4, 8} : cells);
  }
  std::vector<ExtremeCase> cases;
  for (double E : {1.0, 1e3, 1e5, 1e7, 1e9})
    cases.push_back(extreme_case(E, 0.3, 0.0, 0.0));
  for (double nu : {0.0, 0.45, 0.49, 0.499, 0.4999})
    cases.push_back(extreme_case(1e5, nu, 0.0, 0.0));
  for (double h : {1e-6, 1e-4, 1e-2, 1.0, 10.0})
    cases.push_back(extreme_case(1e5, 0.3, h, 0.0));
  cases.push_back(extreme_case(1.0, 0.3, 1.0, 0.0));
  cases.push_back(extreme_case(1e9, 0.3, 1e-2, 0.0));
  cases.push_back(extreme_case(1e5, 0.4999, 1e-2, 0.0));
  cases.push_back(extreme_case(1e5, 0.3, 0.0, 90.0));
  cases.push_back(extreme_case(1e5, 0.3, 1e-2, 90.0));
  // Displacement loads that set the force scale on a slender body: its soft modes amplify a
  // small residual (#44).
  cases.push_back(extreme_case(1e5, 0.3, 0.0, 60.0));
  cases.push_back(extreme_case(1e5, 0.3, 0.0, 0.0, 90.0));
  cases.push_back(extreme_case(1e5, 0.3, 0.0, 0.0, 180.0));
  cases.push_back(extreme_case(1e5, 0.499, 0.0, 0.0, 90.0));

  std::fprintf(table,
               "| case | oracle: Newton tip (rel. residual); beam | solver | iterations | converged (rel. "
               "residual) | inverted tets (min det F) | tip | field error | verdict | time |\n");
  std::fprintf(table, "|---|---|---|---|---|---|---|---|---|---|\n");
  int silent = 0;
  const std::size_t first = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 0;
  const std::size_t last = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : cases.size() - 1;
  for (std::size_t i = first; i <= last && i < cases.size(); ++i) {
    const ExtremeCase& c = cases[i];
    const ExtremeCantilever k = extreme_cantilever(c);
    // The rows first: Newton's reference is only needed for a row the stage would not warn
    // about (at 1 Pa every row inverts, and the reference would take minutes).
    std::vector<ExtremeRow> rows;
    bool needed = false;
    for (ExtremeSolver solver : solvers_for(c)) {
      if (argc > 3 && std::string(argv[3]) != to_string(solver)) continue;
      rows.push_back(run_extreme(c, solver, k, k.stop));
      needed = needed || rows.back().verdict == Verdict::no_oracle;
    }
    std::string oracle_cell = "not needed (every row warned)";
    if (needed) {
      const auto start = std::chrono::steady_clock::now();
      const ExtremeOracle oracle = extreme_oracle(k);
      std::fprintf(stderr, "case %zu: oracle %d iterations, relative residual %.3g, %.1f s\n", i,
                   oracle.report.iterations, oracle.report.relative_residual,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      oracle_cell =
          number(tip_deflection_mm(k, oracle.p)) + " mm (" + number(oracle.report.relative_residual) + ")";
      for (ExtremeRow& row : rows)
        judge_extreme(row, k, oracle);
    }
    const double beam = beam_tip_deflection_mm(c.youngs_modulus_Pa);
    if (c.time_step_s == 0.0 && c.push_mm == 0.0 && beam < 5.0) oracle_cell += "; " + number(beam) + " mm";
    for (const ExtremeRow& row : rows) {
      if (row.verdict == Verdict::silent_wrong) ++silent;
      if (!row.error.empty()) {
        std::fprintf(table, "| %s | %s | %s | | | | | | error: %s | %.2f s |\n", describe(c).c_str(),
                     oracle_cell.c_str(), to_string(row.solver), row.error.c_str(), row.seconds);
      } else {
        std::fprintf(table, "| %s | %s | %s | %d | %s (%s) | %ld (%s) | %s mm | %s | %s | %.2f s |\n",
                     describe(c).c_str(), oracle_cell.c_str(), to_string(row.solver), row.report.iterations,
                     row.report.converged ? "yes" : "no", number(row.report.relative_residual).c_str(),
                     row.inverted.inverted, number(row.inverted.smallest_det_F).c_str(),
                     number(row.tip_mm).c_str(), needed ? number(row.field_error).c_str() : "",
                     to_string(row.verdict), row.seconds);
      }
    }
    std::fflush(table);
  }
  if (silent > 0) std::fprintf(stderr, "solver_extremes: %d rows are silent wrong answers\n", silent);
  return silent > 0 ? 1 : 0;
}
