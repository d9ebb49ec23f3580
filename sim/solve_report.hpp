#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace phantasm {

/// When a solve stops (docs/deformation.md, stopping test; all are explicit in the scene).
/// A solve has converged when its equilibrium residual, the largest gradient row over the free
/// vertices, is at most relative_residual times the force scale of the solve: force_scale_N, the
/// per-vertex force of its loads (the deformation stage sets the weight of the heaviest free
/// vertex, or the elastic force of a vertex moved by a displacement load's increment, whichever
/// is larger), or when that is 0 the largest free gradient row at the start of the solve. The residual test
/// stops a solve by itself; the step criteria (position change, energy decrease) measure a step,
/// not the distance to equilibrium, and stop a solve only when its residual test passes too.
/// A small residual is not a small distance when the loads are stiff springs and the structure
/// is slender (a twisted or pushed bar: its soft modes amplify the residual thousandfold), so a
/// residual that passes is checked by the distance test: the Newton step from the result (the
/// PSD-projected Hessian, sim/newton.hpp) must move no free vertex further than
/// relative_distance times the largest displacement of a free vertex from rest. Local/global
/// finishes with Newton steps where it does not; Newton takes the step anyway.
struct StopCriteria {
  int max_iterations = 100;
  double relative_energy_decrease = 1e-6; ///< (E_k-1 - E_k) / |E_k| below this, with the residual test
  double position_change_m = 1e-7; ///< no free vertex moved further in one iteration, with the residual test
  double gradient_norm_N = 0.0;    ///< stop when the largest free gradient row is below this (0 = off)
  double relative_residual = 1e-3; ///< converged: residual <= this x force scale (0 = never)
  double force_scale_N = 0.0;      ///< the loads' force scale, N (0 = the initial gradient)
  /// converged also needs the Newton step at the result <= this x the largest displacement from
  /// rest (0 = off: the residual test alone)
  double relative_distance = 0.0;
};

/// The residual test: the force scale of a solve from its initial residual (N) and the floor in
/// `stop`, and whether `residual_N` passes against it.
struct ResidualTest {
  double scale_N = 0.0;
  double tolerance = 0.0;
  ResidualTest(const StopCriteria& stop, double initial_residual_N)
      : scale_N(stop.force_scale_N > 0.0 ? stop.force_scale_N : initial_residual_N),
        tolerance(stop.relative_residual) {}
  /// residual_N over the force scale (0 when there is no force at all).
  double relative(double residual_N) const { return scale_N > 0.0 ? residual_N / scale_N : 0.0; }
  bool passes(double residual_N) const {
    return scale_N > 0.0 ? residual_N <= tolerance * scale_N : residual_N <= 0.0;
  }
};

/// A solver's progress detail (core/progress.hpp): "iteration 40, residual 3.1e-04 N".
inline std::string solver_detail(int iteration, double residual_N) {
  char text[64];
  std::snprintf(text, sizeof text, "iteration %d, residual %.2e N", iteration, residual_N);
  return text;
}

/// What a solve did: every solve reports it (into provenance.json).
struct SolveReport {
  std::string solver;
  int iterations = 0;
  std::string stopped_by;         ///< "max_iterations", "residual", "energy", "position", "gradient"
  bool converged = false;         ///< the residual test passed at the result (StopCriteria)
  double relative_residual = 0.0; ///< residual_N over the force scale of the solve
  double force_scale_N = 0.0;     ///< the force scale the residual is measured against
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
  /// The distance test (StopCriteria::relative_distance), when on: the largest free vertex's
  /// Newton step at the result (m; -1: not computed), the largest free displacement from rest
  /// (m), and Newton iterations that finished a local/global solve (counted in `iterations`).
  double equilibrium_distance_m = -1.0;
  double largest_displacement_m = 0.0;
  int newton_iterations = 0;
  /// Unstable equilibria (saddles of the energy: a direction lowers it, as a bar pushed along
  /// its axis buckles) the solve reached and left before it stopped, and their energies (J).
  int saddles_left = 0;
  std::vector<double> saddle_energies_J;
  /// The stability check at the equilibrium the solve stopped at (its distance test's Newton
  /// finish, sim/newton.cpp): the smallest curvature ratio v.H_true v / v.H v the Lanczos steps
  /// found (the energy's curvature over the solver's, which is at most 1; below 0 at a saddle;
  /// NaN when no check ran), the steps taken, and whether the value settled (false: the step
  /// limit came first, and stability is not shown).
  double stability_ratio = std::numeric_limits<double>::quiet_NaN();
  int stability_steps = 0;
  bool stability_settled = false;
  /// The residual (largest free gradient row, N) at each local/global iterate, as the stop test saw
  /// it (Newton steps that finish the solve not included): the report's convergence plot (empty for
  /// the other solvers).
  std::vector<double> residuals_N;
  /// The distance over the largest displacement (0 when nothing moved or not computed).
  double relative_distance() const {
    return equilibrium_distance_m > 0.0 && largest_displacement_m > 0.0
               ? equilibrium_distance_m / largest_displacement_m
               : 0.0;
  }
};

/// Whether a Newton step of `distance_m` passes the distance test of `stop` at a result whose
/// largest free displacement from rest is `largest_displacement_m` (round-off: 1e-12 m passes).
inline bool distance_passes(const StopCriteria& stop, double distance_m, double largest_displacement_m) {
  return stop.relative_distance <= 0.0 ||
         (distance_m >= 0.0 &&
          distance_m <= std::max(stop.relative_distance * largest_displacement_m, 1e-12));
}

/// The residual test's outcome at the result into `report` (converged, relative_residual,
/// force_scale_N), from report.residual_N, and the distance test's when `stop` asks for it
/// (from report.equilibrium_distance_m and largest_displacement_m).
inline void judge_convergence(const ResidualTest& test, SolveReport& report, const StopCriteria& stop = {}) {
  report.force_scale_N = test.scale_N;
  report.relative_residual = test.relative(report.residual_N);
  report.converged = test.passes(report.residual_N) &&
                     distance_passes(stop, report.equilibrium_distance_m, report.largest_displacement_m);
}

/// Called after every iteration with its number, the positions and E(p); its own time is not
/// counted in the report (convergence studies record positions with it).
using IterationObserver = std::function<void(int iteration, const Eigen::MatrixX3d& p, double energy_J)>;

} // namespace phantasm
