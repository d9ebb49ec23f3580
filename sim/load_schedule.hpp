// The frames of the deformation stage: quasi-static load steps or dynamic time steps, the loads
// and obstacles moved along their motion profiles, and one solve per frame. Internal to sim.
#pragma once

#include "core/progress.hpp"
#include "sim/loads.hpp"

#include <Eigen/Core>

namespace phantasm::sim_detail {

/// How far a displacement load or an obstacle has come at time t (dynamic mode), 0..1.
double profile(MotionProfile motion, double period_s, double t);

/// Solves the model frame by frame as the settings say: quasi-static mode applies the loads in
/// load_steps equal increments, each solve starting from the last; dynamic mode steps `frames`
/// times with the loads and obstacles on their motion profiles. p (metres, one row per model
/// vertex) goes from rest to the last frame's positions; every frame's SolveReport, the load
/// and obstacle errors go into `result`, what was solved into `report`.
/// A `rough` solve (a growth calibration's measurement, sim/growth.hpp) stops at the residual
/// test alone, against its own initial residual (a small change of the rest volumes from the
/// last solve's positions is solved to the same fraction as the first change from rest): no
/// distance test, and none of the Newton steps that finish it. The calibration's last solve is
/// never rough.
/// @throws SettingError for a position-based solver in quasi-static mode
/// @throws InputError when nothing holds the model in quasi-static mode, or when a solve goes non-finite
void solve_frames(const DeformationSettings& deformation, ElasticModel& model, Loads& loads,
                  Eigen::MatrixX3d& p, PhantomDeformation& result, StageReport& report, Reporter& reporter,
                  bool rough = false);

} // namespace phantasm::sim_detail
