// Stop criteria of a solve, the report every solver returns (into provenance.json), and the
// per-iteration observer convergence studies use.
#pragma once

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace phantasm {

/// When a solve stops (docs/method.md section 2.5; all three are explicit in the scene).
struct StopCriteria {
  int max_iterations = 100;
  double relative_energy_decrease = 1e-6; ///< stop when (E_k-1 - E_k) / |E_k| falls below this
  double position_change_m = 1e-7;        ///< stop when no free vertex moved further in one iteration
  double gradient_norm_N = 0.0;           ///< stop when the largest free gradient row is below this (0 = off)
};

/// What a solve did: every solve reports it (into provenance.json).
struct SolveReport {
  std::string solver;
  int iterations = 0;
  std::string stopped_by; ///< "max_iterations", "energy", "position", "gradient"
  double initial_energy_J = 0.0;
  double final_energy_J = 0.0;
  double residual_N = 0.0;        ///< largest gradient row norm over free vertices at the result
  std::vector<double> energies_J; ///< E(p_k) for k = 0 .. iterations (when recorded)
  std::vector<double> seconds;    ///< solver time after each iteration (when recorded; observers excluded)
  double local_seconds = 0.0;     ///< time in local steps (projections and right-hand side)
  double global_seconds = 0.0;    ///< time in global steps (triangular solves)
  int contacts = 0;               ///< free vertices inside an obstacle at the result
  long contact_changes = 0;       ///< vertices whose contacts came or went during the solve
  long rank_updates = 0;          ///< rank-one updates/downdates of the factor so far
};

/// Called after every iteration with its number, the positions and E(p); its own time is not
/// counted in the report (convergence studies record positions with it).
using IterationObserver = std::function<void(int iteration, const Eigen::MatrixX3d& p, double energy_J)>;

} // namespace phantasm
