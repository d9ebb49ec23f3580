// The extremes table (#16): the cantilever of tests/sim (20 x 20 x 100 mm, its x-min end held,
// gravity along -z, 1000 kg/m^3, 4 x 4 x 20 cells of 5 tets) at extreme Young's moduli, Poisson
// ratios, time steps and loads that invert it, solved by every solver with the stopping test a
// scene gets by default (sim/load_schedule.cpp) and compared with Newton's converged answer on
// the same mesh (and, where the beam bends little, Euler-Bernoulli). Every row must be a
// converged answer within `k_field_tolerance` of the oracle, or say that it is not (the solve did
// not converge, or tets are inverted: the deformation stage's warnings): never a silent wrong
// field. Shared by bench/solver_extremes.cpp (the table) and tests/sim/test_solver_extremes.cpp.
#pragma once

#include "anatomy/structured_mesh.hpp"
#include "sim/build_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/sim_settings.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::bench {

/// A converged answer must lie within this fraction of the oracle's largest displacement of
/// every vertex (the field, not only the tip).
constexpr double k_field_tolerance = 0.01;

enum class ExtremeSolver { local_global, jacobi_chebyshev, newton, xpbd, gauss_seidel_pbd };

inline const char* to_string(ExtremeSolver s) {
  switch (s) {
  case ExtremeSolver::local_global: return "local_global";
  case ExtremeSolver::jacobi_chebyshev: return "jacobi_chebyshev";
  case ExtremeSolver::newton: return "newton";
  case ExtremeSolver::xpbd: return "xpbd";
  case ExtremeSolver::gauss_seidel_pbd: return "gauss_seidel_pbd";
  }
  return "?";
}

/// One load case of the cantilever.
struct ExtremeCase {
  double youngs_modulus_Pa = 1e5;
  double poisson_ratio = 0.3;
  double time_step_s = 0.0; ///< 0: quasi-static; else one implicit Euler step from rest
  /// > 0: the free end's vertices are tied (displacement springs of 10^4 x the nominal stiffness,
  /// as a scene's displacement load) to their rest places moved this far along -x, towards the
  /// held end (mm); gravity acts too
  double push_mm = 0.0;
  /// != 0: the free end's vertices are tied the same way to their rest places turned by this
  /// angle about the bar's axis (through the free face's centre; with push_mm, then pushed)
  double twist_deg = 0.0;
  std::optional<VolumeFormulation> volume; ///< unset: the scene default (deformation.volume)
  int cells_across = 4;                    ///< the bar's cells across (5 times as many along it)
};

/// The case of a material, a time step (0: quasi-static) and end loads, with the scene's default
/// volume term and 4 cells across.
inline ExtremeCase extreme_case(double youngs_modulus_Pa, double poisson_ratio, double time_step_s,
                                double push_mm, double twist_deg = 0.0) {
  ExtremeCase c;
  c.youngs_modulus_Pa = youngs_modulus_Pa;
  c.poisson_ratio = poisson_ratio;
  c.time_step_s = time_step_s;
  c.push_mm = push_mm;
  c.twist_deg = twist_deg;
  return c;
}

/// The cantilever of a case as the deformation stage would build it.
struct ExtremeCantilever {
  ElasticModel model;
  StepInertia inertia;
  StopCriteria stop;         ///< the scene defaults, with the stage's force scale
  std::vector<int> free_end; ///< vertices of the x-max face
};

inline ExtremeCantilever extreme_cantilever(const ExtremeCase& c) {
  const int n = c.cells_across;
  const TetMesh mesh = structured_box(Eigen::Vector3d(100, 20, 20), Eigen::Vector3i(5 * n, n, n),
                                      Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  ExtremeCantilever k;
  add_body(k.model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(c.youngs_modulus_Pa, c.poisson_ratio),
           1000.0);
  // The bulk term where a scene puts it by default (deformation.volume), as the stage does.
  apply_volume_formulation(k.model, c.volume ? *c.volume : DeformationSettings{}.volume, mesh, 0);
  const Eigen::MatrixX3d& rest = k.model.rest_positions_m;
  const Eigen::RowVector3d g(0, 0, -9.81);
  const SolverSettings defaults;
  k.stop.max_iterations = defaults.max_iterations;
  k.stop.relative_energy_decrease = defaults.relative_energy_tolerance;
  k.stop.position_change_m = 1e-3 * defaults.position_tolerance_mm;
  k.stop.relative_residual = defaults.relative_residual_tolerance;
  k.stop.relative_distance = defaults.relative_residual_tolerance; // as sim/load_schedule.cpp
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    if (rest(v, 0) < -0.05 + 1e-9) k.model.fixed[static_cast<std::size_t>(v)] = 1;
    if (rest(v, 0) > 0.05 - 1e-9) k.free_end.push_back(static_cast<int>(v));
    if (!k.model.fixed[static_cast<std::size_t>(v)])
      k.stop.force_scale_N = std::max(k.stop.force_scale_N, k.model.masses_kg[v] * g.norm());
  }
  if (c.push_mm > 0.0 || c.twist_deg != 0.0) {
    const double stiffness = 1e4 * sim_detail::nominal_stiffness(k.model);
    const Eigen::Vector3d centre(0.05, 0.0, 0.0);
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(c.twist_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
    double moved_m = 0.0;
    for (int v : k.free_end) {
      PointConstraint p;
      p.vertices = {v, 0, 0, 0};
      p.coefficients = Eigen::Vector4d(1, 0, 0, 0);
      p.count = 1;
      p.stiffness_N_m = stiffness;
      const Eigen::Vector3d x = rest.row(v).transpose();
      p.target_m = centre + turn * (x - centre) - Eigen::Vector3d(1e-3 * c.push_mm, 0, 0);
      moved_m = std::max(moved_m, (p.target_m - x).norm());
      k.model.points.push_back(p);
    }
    // the stage's force scale of a displacement load (sim/load_schedule.cpp)
    k.stop.force_scale_N = std::max(k.stop.force_scale_N, sim_detail::nominal_stiffness(k.model) * moved_m);
  }
  if (c.time_step_s > 0.0) { // one dynamic step from rest: gravity through the inertial target
    const double h = c.time_step_s;
    k.inertia.weight = 1.0 / (h * h);
    k.inertia.target_m = rest;
    for (Eigen::Index v = 0; v < rest.rows(); ++v)
      if (!k.model.fixed[static_cast<std::size_t>(v)]) k.inertia.target_m.row(v) += h * h * g;
  } else {
    k.model.external_forces_N = k.model.masses_kg * g;
  }
  return k;
}

/// Euler-Bernoulli's tip deflection of the cantilever under its weight, w = q L^4 / (8 E I), mm.
inline double beam_tip_deflection_mm(double youngs_modulus_Pa) {
  const double side = 0.02, length = 0.1, q = 1000.0 * 9.81 * side * side, inertia = std::pow(side, 4) / 12.0;
  return 1e3 * q * std::pow(length, 4) / (8.0 * youngs_modulus_Pa * inertia);
}

/// The mean downward displacement of the free end, mm.
inline double tip_deflection_mm(const ExtremeCantilever& k, const Eigen::MatrixX3d& p) {
  double sum = 0.0;
  for (int v : k.free_end)
    sum += k.model.rest_positions_m(v, 2) - p(v, 2);
  return 1e3 * sum / static_cast<double>(k.free_end.size());
}

/// The smallest det F of the tets, and how many are inverted (det F <= 0), as the deformation
/// stage checks every body (sim/deform_phantom.cpp).
struct Inversions {
  double smallest_det_F = 1.0;
  long inverted = 0;
};

inline Inversions inversions(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  Inversions result;
  for (const TetElement& t : model.tets) {
    Eigen::Matrix<double, 3, 4> X;
    for (int k = 0; k < 4; ++k)
      X.col(k) = p.row(t.vertices[static_cast<std::size_t>(k)]).transpose();
    const double det = (X * t.Q).determinant();
    result.smallest_det_F = std::min(result.smallest_det_F, det);
    if (!(det > 0.0)) ++result.inverted;
  }
  return result;
}

/// Newton run towards a relative residual of 1e-7 within 300 iterations (the oracle of a case;
/// at 1 GPa round-off in the stresses stops it near 4e-8; a bar pushed 60 mm takes 173).
struct ExtremeOracle {
  Eigen::MatrixX3d p;
  SolveReport report;
  double largest_displacement_m = 0.0;
};

inline ExtremeOracle extreme_oracle(const ExtremeCantilever& k) {
  ExtremeOracle o;
  o.p = k.model.rest_positions_m;
  StopCriteria tight = k.stop;
  tight.max_iterations = 300;
  tight.relative_residual = 1e-7;
  tight.relative_energy_decrease = 0.0;
  tight.position_change_m = 0.0;
  o.report = newton_solve(k.model, k.inertia, o.p, tight);
  o.largest_displacement_m = (o.p - k.model.rest_positions_m).rowwise().norm().maxCoeff();
  return o;
}

/// A row's verdict.
enum class Verdict {
  converged_and_right, ///< converged, nothing inverted, within k_field_tolerance of the oracle
  warned,              ///< not converged or inverted tets: the stage warns (an error with --strict)
  refused,             ///< the solver throws (e.g. non-finite positions): the stage stops
  silent_wrong,        ///< converged, nothing inverted, and off the oracle: must not happen
  no_oracle,           ///< converged, nothing inverted, but the oracle itself did not converge
};

inline const char* to_string(Verdict v) {
  switch (v) {
  case Verdict::converged_and_right: return "converged, matches";
  case Verdict::warned: return "warned";
  case Verdict::refused: return "error";
  case Verdict::silent_wrong: return "SILENT WRONG";
  case Verdict::no_oracle: return "converged, no oracle";
  }
  return "?";
}

/// One solver on one case.
struct ExtremeRow {
  ExtremeCase c;
  ExtremeSolver solver = ExtremeSolver::local_global;
  SolveReport report;
  Inversions inverted;
  double tip_mm = 0.0, oracle_tip_mm = 0.0;
  double field_error = 0.0; ///< largest vertex distance to the oracle over its largest displacement
  double seconds = 0.0;
  std::string error;  ///< what the solver threw
  Eigen::MatrixX3d p; ///< the result, m
  Verdict verdict = Verdict::warned;
};

/// The oracle must be far below the default tolerance to judge a row by it.
inline bool oracle_converged(const ExtremeOracle& o) {
  return o.report.relative_residual <= 1e-5;
}

/// One solver on a case with the stop criteria `stop` (the scene defaults, k.stop, unless a test
/// caps the iterations): the report, the positions and their inversions; the verdict waits for
/// judge_extreme, unless the stage would warn anyway (not converged, inverted) or the solver
/// threw.
inline ExtremeRow run_extreme(const ExtremeCase& c, ExtremeSolver solver, const ExtremeCantilever& k,
                              const StopCriteria& stop) {
  ExtremeRow row;
  row.c = c;
  row.solver = solver;
  Eigen::MatrixX3d& p = row.p;
  p = k.model.rest_positions_m;
  const Eigen::MatrixX3d target = k.inertia.weight > 0.0 ? k.inertia.target_m : p;
  const auto start = std::chrono::steady_clock::now();
  try {
    switch (solver) {
    case ExtremeSolver::local_global: {
      LocalGlobalSolver s(k.model, k.inertia.weight, 1);
      row.report = s.solve(p, target, stop);
      break;
    }
    case ExtremeSolver::jacobi_chebyshev: {
      LocalGlobalSolver s(k.model, k.inertia.weight, 1);
      row.report = s.solve_jacobi_chebyshev(p, target, stop);
      break;
    }
    case ExtremeSolver::newton: row.report = newton_solve(k.model, k.inertia, p, stop); break;
    case ExtremeSolver::xpbd:
    case ExtremeSolver::gauss_seidel_pbd:
      // they start from the prediction (sim/load_schedule.cpp)
      for (Eigen::Index v = 0; v < p.rows(); ++v)
        if (!k.model.fixed[static_cast<std::size_t>(v)]) p.row(v) = target.row(v);
      row.report = position_based_solve(
          solver == ExtremeSolver::xpbd ? PositionBasedVariant::xpbd : PositionBasedVariant::gauss_seidel_pbd,
          k.model, k.inertia, p, stop);
      break;
    }
    // the deformation stage stops on non-finite positions (sim/load_schedule.cpp)
    if (!p.allFinite()) throw std::runtime_error("non-finite positions");
  } catch (const std::exception& e) {
    row.error = e.what();
  }
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!row.error.empty()) {
    row.verdict = Verdict::refused;
    return row;
  }
  row.inverted = inversions(k.model, p);
  row.tip_mm = tip_deflection_mm(k, p);
  row.verdict = !row.report.converged || row.inverted.inverted > 0 ? Verdict::warned : Verdict::no_oracle;
  return row;
}

/// A row against its case's oracle: the field error, and for a converged row with nothing
/// inverted whether it is right or a silent wrong answer.
inline void judge_extreme(ExtremeRow& row, const ExtremeCantilever& k, const ExtremeOracle& oracle) {
  if (!row.error.empty()) return;
  row.oracle_tip_mm = tip_deflection_mm(k, oracle.p);
  const double distance = (row.p - oracle.p).rowwise().norm().maxCoeff();
  row.field_error = oracle.largest_displacement_m > 0.0 ? distance / oracle.largest_displacement_m : distance;
  if (row.verdict != Verdict::no_oracle || !oracle_converged(oracle)) return;
  row.verdict = row.field_error <= k_field_tolerance ? Verdict::converged_and_right : Verdict::silent_wrong;
}

/// The solvers a case can be given: position-based ones step in time only.
inline std::vector<ExtremeSolver> solvers_for(const ExtremeCase& c) {
  std::vector<ExtremeSolver> s{ExtremeSolver::local_global, ExtremeSolver::jacobi_chebyshev,
                               ExtremeSolver::newton};
  if (c.time_step_s > 0.0) {
    s.push_back(ExtremeSolver::xpbd);
    s.push_back(ExtremeSolver::gauss_seidel_pbd);
  }
  return s;
}

} // namespace phantasm::bench
