// Growth and atrophy: a change of rest volume of an organ's tets (multiplicative growth,
// F = Fe Fg), which the surrounding tissue answers mechanically. Internal to sim.
#pragma once

#include "core/stage_report.hpp"
#include "geometry/tet_mesh.hpp"
#include "sim/build_model.hpp"
#include "sim/elastic_model.hpp"
#include "sim/sim_settings.hpp"

#include <cstddef>
#include <vector>

namespace phantasm::sim_detail {

/// Applies every growth load of `deformation` to the tets of one body (`mesh`), appended to
/// `built.model` from `first_tet` with `organ_of_tet` (organ table indices) for each: a tet of a
/// grown organ, or whose centroid (rest state) lies in a grown atlas region, gets
/// Fg = (1 + g)^(1/3) I, so its elastic energy reads Fe = F Fg^-1 (Q / (1 + g)^(1/3)) and its
/// weights are those of its grown rest volume V (1 + g). A region's change takes precedence
/// over its organ's. Counts the tets grown per load into `built.grown_tets` (one entry per load)
/// and raises `built.region_growth_moved_m` to the rest-surface motion of each region grown.
/// @throws SettingError (deformation.volume) for growth with vertex_stars, whose bulk term is
///   not per tet; (deformation.loads[k].region) as growth_region_labels
void apply_growth(const DeformationSettings& deformation, const OrganTable& organs,
                  const std::vector<std::size_t>& organ_of_tet, const TetMesh& mesh, std::size_t first_tet,
                  BodyModel& built);

/// The largest miss (absolute) of a growth load's volume change in the result, and the most
/// solves that may meet it (recalibrate_growth).
inline constexpr double k_growth_tolerance = 1e-3;
inline constexpr int k_growth_rounds = 8;
/// The miss a rough solve must be within before the exact solve that decides (a quarter of the
/// tolerance: the exact solve seldom moves the tets' volume by more than that).
inline constexpr double k_rough_growth_tolerance = 0.25 * k_growth_tolerance;

/// The solves of a growth calibration so far (recalibrate_growth): per solve the rest-volume
/// ratio of each growth load's tets, the volume ratio they reached and the positions (m), the
/// first entry the rest state (no growth reaches no change, at rest).
struct GrowthCalibration {
  std::vector<Eigen::VectorXd> ratios, reached;
  std::vector<Eigen::MatrixX3d> positions_m;
  /// The residual of the first solve at its start (N): the rough solves stop at its
  /// relative_residual_tolerance times this (rough_solve_settings).
  double first_residual_N = 0.0;
};

/// A growth load prescribes its tets' volume change in the result: after the solve of `round`
/// (0 first), the volume each load's tets reach in `p_m` (m) against their rest volume before
/// growth. Where one misses 1 + g by more than k_growth_tolerance, the rest-volume ratios move to
/// where the reached ratios, taken as linear in them, meet every prescription: through the last
/// solves of `calibration` (as many as there are loads, the rest state among them: the loads'
/// couplings, a region shrinking as its neighbour grows, are measured, not ignored), or, before
/// there are enough, per load along the secant of its own reached ratio; `p_m` moves by the same
/// combination of the last solves' positions (the start of the next solve, about its result);
/// true says to solve again. Where all meet k_rough_growth_tolerance after a `rough` solve
/// (sim/load_schedule.hpp: no finishing Newton steps), true says to solve the same rest volumes
/// again exactly; after an exact solve, each load's figures go into `report` and false says
/// done: only an exact solve's volumes are ever reported as met.
/// @throws SettingError (deformation.loads[k].organ or .region) when a load still misses after
///   k_growth_rounds solves or inverts its tets: no room to give way
bool recalibrate_growth(const DeformationSettings& deformation, BodyModel& built, Eigen::MatrixX3d& p_m,
                        int round, bool rough, StageReport& report, GrowthCalibration& calibration);

/// The settings of a rough calibration solve from `p_m`: the scene's, with the residual
/// tolerance that stops it at the residual the first solve stopped at (its tolerance times
/// calibration.first_residual_N), so that a solve started near its result takes the few
/// iterations it needs, not a thousandfold reduction of a small start.
DeformationSettings rough_solve_settings(const DeformationSettings& deformation, const ElasticModel& model,
                                         const Eigen::MatrixX3d& p_m, const GrowthCalibration& calibration);

/// Checks that every growth load grew some tets and reports each one as modelled.
/// @throws SettingError (deformation.loads[k].organ, or .region) for an organ or regions no
///   simulated tet lies in
void report_growth(const DeformationSettings& deformation, const std::vector<std::size_t>& grown_tets,
                   StageReport& report);

/// The largest distance (m) a growth load moves the rest surface of its organ, about: the
/// organ's extent times |(1 + g)^(1/3) - 1| (the scale of the residual test's force).
double growth_displacement_m(const LoadSettings& load, const Eigen::MatrixX3d& organ_rest_mm);

} // namespace phantasm::sim_detail
