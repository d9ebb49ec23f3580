// The frame loop of the deformation stage: the solver the scene asks for, the loads and obstacles
// moved per frame (load increments or motion profiles), the solves, and their report.
#include "sim/load_schedule.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "sim/build_model.hpp"
#include "sim/prepared_solver.hpp"
#include "sim/solver_type.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace phantasm::sim_detail {
namespace {

/// The solver of the scene, and what kind of stepping it does.
struct FrameSolver {
  bool dynamic = false;
  double h = 0.0; ///< time step, s
  int frames = 0; ///< dynamic frames, or quasi-static load steps
  StopCriteria stop;
  std::unique_ptr<PreparedSolver> solver; ///< the scene's method (sim/solvers/)
};

/// @throws SettingError for a position-based solver in quasi-static mode (which the scene's
/// validation rejects first)
/// @throws InputError for a model nothing holds (a local/global matrix that cannot be factored)
FrameSolver make_frame_solver(const DeformationSettings& deformation, const ElasticModel& model) {
  FrameSolver s;
  const SolverSettings& solver = deformation.solver;
  s.dynamic = deformation.mode == DeformationMode::dynamic;
  if (solver_type(solver.method).steps_in_time && !s.dynamic) {
    throw SettingError("deformation.solver.method",
                       std::string(to_string(solver.method)) +
                           " steps in time; it cannot solve for a static equilibrium");
  }
  s.stop.max_iterations = solver.max_iterations;
  s.stop.relative_energy_decrease = solver.relative_energy_tolerance;
  s.stop.position_change_m = k_mm * solver.position_tolerance_mm;
  s.stop.relative_residual = solver.relative_residual_tolerance;
  // The distance test with the same tolerance: the Newton step at the result within this
  // fraction of the largest displacement (a small residual is not a small distance where stiff
  // springs twist or push a slender body).
  s.stop.relative_distance = solver.relative_residual_tolerance;
  s.h = deformation.time_step_s;
  // Quasi-static solves apply the loads in load_steps equal increments, each starting from the
  // last; dynamic mode makes one solve per frame.
  s.frames = s.dynamic ? deformation.frames : deformation.load_steps;
  try {
    s.solver = solver_entry(solver.method).make(model, s.dynamic ? 1.0 / (s.h * s.h) : 0.0, solver);
  } catch (const Cancelled&) {
    throw;
  } catch (const std::runtime_error& error) {
    throw InputError(std::string("deformation: ") + error.what() +
                     "; in quasi-static mode put each loaded organ inside a fixed organ or list it in "
                     "deformation.fixed");
  }
  return s;
}

/// The displacement loads' targets and the obstacles where they are at frame `frame`.
void move_loads(const DeformationSettings& deformation, const FrameSolver& s, int frame, Loads& loads,
                ElasticModel& model) {
  const double t = (frame + 1) * s.h;
  const double increment = static_cast<double>(frame + 1) / s.frames;
  for (PushedPoints& push : loads.pushes) {
    const double amount = s.dynamic ? profile(push.load->motion, push.load->period_s, t) : increment;
    for (std::size_t k = 0; k < push.constraints.size(); ++k)
      model.points[push.constraints[k]].target_m = loaded_position_m(*push.load, push.rest_m[k], amount);
  }
  if (!model.obstacles.empty()) {
    place_obstacles(
        deformation.obstacles,
        [&](const ObstacleSettings& o) { return s.dynamic ? profile(o.motion, o.period_s, t) : increment; },
        model);
  }
}

/// The last solve, the displacement loads' error and the obstacles' penetration into `report`.
void report_solves(const FrameSolver& s, const ElasticModel& model, const Eigen::MatrixX3d& p,
                   PhantomDeformation& result, StageReport& report) {
  const SolveReport& last = result.solves.back();
  report.modelled.push_back(
      std::string(last.solver) + " " +
      (s.dynamic      ? "dynamic, " + std::to_string(s.frames) + " frames of " + format_number(s.h) + " s"
       : s.frames > 1 ? "quasi-static in " + std::to_string(s.frames) + " load steps"
                      : "quasi-static") +
      ": last solve " + std::to_string(last.iterations) + " iterations, stopped by " + last.stopped_by +
      ", residual " + format_number(last.residual_N) + " N");
  // The equilibrium's stability as the check saw it: a ratio near 1 is far from buckling, one
  // near 0 close to it.
  if (last.stability_steps > 0) {
    const std::string ratio = format_number(last.stability_ratio);
    const std::string steps = std::to_string(last.stability_steps) + " Lanczos steps";
    const std::string line = "stability of the equilibrium the last solve stopped at: ";
    if (!last.stability_settled) {
      report.modelled.push_back(line + "not shown, the smallest curvature ratio had not settled after " +
                                steps + " (" + ratio + " so far)");
    } else if (last.stability_ratio > 0.0) {
      report.modelled.push_back(line + "stable, the energy's smallest curvature is " + ratio +
                                " of the solver's (" + steps + ")");
    } else { // a saddle the solve left is checked again where it stops: this one it could not leave
      report.warnings.push_back(line + "a saddle (curvature ratio " + ratio + ", " + steps +
                                ") that no step along its direction of negative curvature lowered: the "
                                "body may buckle from the result");
    }
    report.accuracy["solver smallest curvature ratio"] = last.stability_ratio;
  }
  report.accuracy["solver residual N"] = last.residual_N;
  report.accuracy["solver relative residual"] = last.relative_residual;
  report.accuracy["solver iterations"] = last.iterations;
  // A solve that stopped short of equilibrium gives a ground truth nobody can vouch for: say so,
  // and by how much (the residual over the force scale, the Newton step over the displacement).
  int unconverged = 0;
  const SolveReport* worst = nullptr;
  double farthest = 0.0;
  for (const SolveReport& solve : result.solves) {
    farthest = std::max(farthest, solve.relative_distance());
    if (solve.converged) continue;
    ++unconverged;
    if (!worst || solve.relative_residual > worst->relative_residual) worst = &solve;
  }
  report.accuracy["solver relative distance"] = farthest;
  // Where a solve stopped at an unstable equilibrium (a saddle: a pushed body held straight
  // where it buckles), the solver left it for a stable one: say where it was.
  for (std::size_t i = 0; i < result.solves.size(); ++i) {
    const SolveReport& solve = result.solves[i];
    if (solve.saddle_energies_J.empty()) continue;
    report.modelled.push_back("solve " + std::to_string(i + 1) + " reached an unstable equilibrium (energy " +
                              format_number(solve.saddle_energies_J.front()) +
                              " J; a direction lowers it: the body buckles) and left it for a stable one (" +
                              format_number(solve.final_energy_J) + " J)");
  }
  if (worst) {
    double distance = 0.0;
    for (const SolveReport& solve : result.solves)
      if (!solve.converged) distance = std::max(distance, solve.relative_distance());
    report.warnings.push_back(
        std::to_string(unconverged) + " of " + std::to_string(result.solves.size()) + " " + last.solver +
        " solves did not converge: relative residual up to " + format_number(worst->relative_residual) +
        " (tolerance " + format_number(s.stop.relative_residual) + "), a Newton step from the result up to " +
        format_number(100.0 * distance) + " % of the largest displacement (tolerance " +
        format_number(100.0 * s.stop.relative_distance) + " %) after " + std::to_string(worst->iterations) +
        " iterations, stopped by " + worst->stopped_by + "; raise deformation.solver.max_iterations");
  }
  for (const PointConstraint& c : model.points) {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (int k = 0; k < c.count; ++k)
      x += c.coefficients[k] * p.row(c.vertices[static_cast<std::size_t>(k)]).transpose();
    result.attachment_error_mm = std::max(result.attachment_error_mm, (x - c.target_m).norm() / k_mm);
  }
  report.accuracy["displacement load error mm"] = result.attachment_error_mm;
  if (!model.obstacles.empty()) {
    double deepest = 0.0;
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      if (model.fixed[static_cast<std::size_t>(v)]) continue;
      for (const Obstacle& o : model.obstacles)
        deepest = std::max(deepest, -o.signed_distance(p.row(v).transpose()));
    }
    result.obstacle_penetration_mm = deepest / k_mm;
    report.accuracy["obstacle penetration mm"] = result.obstacle_penetration_mm;
    report.accuracy["vertices in contact"] = last.contacts;
    report.modelled.push_back(
        std::to_string(last.contacts) + " vertices in contact with obstacles at the end (" +
        std::to_string(last.rank_updates) + " rank-one updates of the factor as contacts came and went)");
  }
}

} // namespace

double profile(MotionProfile motion, double period_s, double t) {
  switch (motion) {
  case MotionProfile::constant: return 1.0;
  case MotionProfile::ramp: return std::min(1.0, t / period_s);
  case MotionProfile::sine: return 0.5 * (1.0 - std::cos(2.0 * M_PI * t / period_s));
  }
  return 1.0;
}

void solve_frames(const DeformationSettings& deformation, ElasticModel& model, Loads& loads,
                  Eigen::MatrixX3d& p, PhantomDeformation& result, StageReport& report, Reporter& reporter,
                  bool rough) {
  FrameSolver s = make_frame_solver(deformation, model);
  const double h = s.h;
  const Eigen::MatrixX3d& acceleration = loads.acceleration;
  if (!s.dynamic) model.external_forces_N = model.masses_kg.asDiagonal() * acceleration;
  // The residual test's force scale, per vertex: the weight of the heaviest free vertex, or the
  // elastic force that moves a vertex by one increment of a displacement load (its translation
  // and turn) or an obstacle (not the stiff springs' pull at the start, which only says how far
  // the targets are).
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)])
      s.stop.force_scale_N = std::max(s.stop.force_scale_N, model.masses_kg[v] * acceleration.row(v).norm());
  }
  double moved_m = 0.0;
  for (const PushedPoints& push : loads.pushes)
    for (const Eigen::Vector3d& rest : push.rest_m)
      moved_m = std::max(moved_m, (loaded_position_m(*push.load, rest, 1.0) - rest).norm());
  if (!model.obstacles.empty())
    for (const ObstacleSettings& o : deformation.obstacles)
      moved_m = std::max(moved_m, k_mm * o.displacement_mm.norm());
  moved_m = std::max(moved_m, loads.growth_moved_m);
  s.stop.force_scale_N = std::max(s.stop.force_scale_N, nominal_stiffness(model) * moved_m / s.frames);
  if (rough) { // the residual test against the solve's initial residual: what the last change made
    s.stop.force_scale_N = 0.0;
    s.stop.relative_distance = 0.0;
  }
  Eigen::MatrixX3d velocity = Eigen::MatrixX3d::Zero(p.rows(), 3);
  ProgressBar progress(reporter, "deform", static_cast<std::size_t>(s.frames));
  for (int frame = 0; frame < s.frames; ++frame) {
    throw_if_cancelled();
    move_loads(deformation, s, frame, loads, model);
    StepInertia inertia;
    if (s.dynamic) {
      inertia.weight = 1.0 / (h * h);
      inertia.target_m = p + h * velocity + h * h * acceleration;
    }
    const Eigen::MatrixX3d previous = p;
    SolveReport solve = s.solver->solve(model, inertia, p, s.stop);
    if (!p.allFinite()) throw InputError("deformation: the solver produced non-finite positions");
    if (s.dynamic) velocity = (p - previous) / h;
    result.solves.push_back(std::move(solve));
    progress.advance();
  }
  report_solves(s, model, p, result, report);
  report.status = "done";
}

} // namespace phantasm::sim_detail
