// Growth and atrophy as a change of the tets' rest volume: Fg = (1 + g)^(1/3) I per grown tet.
#include "sim/growth.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "sim/body_embedding.hpp"
#include "sim/growth_regions.hpp"
#include "sim/load_type.hpp"

#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace phantasm::sim_detail {
namespace {

/// The steepest secant slope (reached ratio over rest ratio) a calibration step trusts: a grown
/// region's tets reach at most their own rest-volume change, less what the tissue around
/// resists, plus what grown neighbours push on them.
constexpr double k_largest_growth_slope = 2.0;

std::string growth_load_key(std::size_t k, const LoadSettings& load) {
  return "deformation.loads[" + std::to_string(k) + "]." + (load.regions.empty() ? "organ" : "region");
}

} // namespace

void apply_growth(const DeformationSettings& deformation, const OrganTable& organs,
                  const std::vector<std::size_t>& organ_of_tet, const TetMesh& mesh, std::size_t first_tet,
                  BodyModel& built) {
  built.grown_tets.resize(deformation.loads.size(), 0);
  built.growth_rest_ratio.resize(deformation.loads.size(), 1.0);
  built.growth_load_of_tet.resize(first_tet + organ_of_tet.size(), -1);
  const std::vector<std::vector<std::int32_t>> region_labels = growth_region_labels(deformation);
  // The load growing each tet: an organ's, then a region's (which takes precedence).
  std::vector<std::optional<std::size_t>> load_of_tet(organ_of_tet.size());
  for (std::size_t k = 0; k < deformation.loads.size(); ++k) {
    const LoadSettings& load = deformation.loads[k];
    if (!load_type(load.kind).changes_rest_volume) continue;
    if (deformation.volume == VolumeFormulation::vertex_star) {
      throw SettingError("deformation.volume",
                         "expected per_tet or tet_groups with a growth load (a vertex star's bulk term "
                         "spans organs), found 'vertex_stars'");
    }
    const int organ = load.regions.empty() ? organs.index_of(load.organ) : -1;
    if (organ < 0) continue; // regions below; an organ no tet carries: report_growth says so
    for (std::size_t t = 0; t < organ_of_tet.size(); ++t)
      if (organ_of_tet[t] == static_cast<std::size_t>(organ)) load_of_tet[t] = k;
  }
  if (deformation.region_atlas) {
    const RegionAtlas& atlas = *deformation.region_atlas;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int c = 0; c < 4; ++c)
        centroid += 0.25 * mesh.vertices.row(mesh.tets(t, c)).transpose();
      const std::int32_t label = atlas.label_at(centroid);
      if (label == 0) continue;
      for (std::size_t k = 0; k < region_labels.size(); ++k)
        if (std::find(region_labels[k].begin(), region_labels[k].end(), label) != region_labels[k].end())
          load_of_tet[static_cast<std::size_t>(t)] = k;
    }
  }
  // Per region load, the tets it grows: their extent gives the residual's scale.
  std::vector<std::vector<Eigen::Index>> region_tets(deformation.loads.size());
  for (std::size_t t = 0; t < load_of_tet.size(); ++t) {
    if (!load_of_tet[t]) continue;
    const std::size_t k = *load_of_tet[t];
    const LoadSettings& load = deformation.loads[k];
    // Fe = F Fg^-1 = X Q / s: the tet's elastic terms read Q / s, and they weigh the grown
    // rest volume V s^3 = V (1 + g) (energy per unit of grown volume).
    const double volume_ratio = 1.0 + load.volume_change;
    TetElement& e = built.model.tets[first_tet + t];
    e.Q /= std::cbrt(volume_ratio);
    e.rest_volume_m3 *= volume_ratio;
    e.strain_weight *= volume_ratio;
    e.volume_weight *= volume_ratio;
    ++built.grown_tets[k];
    built.growth_load_of_tet[first_tet + t] = static_cast<int>(k);
    built.growth_rest_ratio[k] = volume_ratio;
    if (!load.regions.empty()) region_tets[k].push_back(static_cast<Eigen::Index>(t));
  }
  for (std::size_t k = 0; k < region_tets.size(); ++k) {
    Eigen::MatrixX3d vertices(4 * static_cast<Eigen::Index>(region_tets[k].size()), 3);
    for (std::size_t n = 0; n < region_tets[k].size(); ++n)
      for (int c = 0; c < 4; ++c)
        vertices.row(4 * static_cast<Eigen::Index>(n) + c) =
            mesh.vertices.row(mesh.tets(region_tets[k][n], c));
    built.region_growth_moved_m =
        std::max(built.region_growth_moved_m, growth_displacement_m(deformation.loads[k], vertices));
  }
}

namespace {

/// Per load, the rest volume of its tets before growth and their volume at p_m (m^3).
struct GrowthVolumes {
  std::vector<double> rest, deformed;
};

GrowthVolumes growth_volumes(const BodyModel& built, const Eigen::MatrixX3d& p_m) {
  const std::size_t loads = built.growth_rest_ratio.size();
  GrowthVolumes v{std::vector<double>(loads, 0.0), std::vector<double>(loads, 0.0)};
  for (std::size_t t = 0; t < built.growth_load_of_tet.size(); ++t) {
    const int k = built.growth_load_of_tet[t];
    if (k < 0) continue;
    const TetElement& e = built.model.tets[t];
    const auto& x = e.vertices;
    const Eigen::Vector3d a = p_m.row(x[1]) - p_m.row(x[0]), b = p_m.row(x[2]) - p_m.row(x[0]),
                          c = p_m.row(x[3]) - p_m.row(x[0]);
    v.deformed[static_cast<std::size_t>(k)] += a.cross(b).dot(c) / 6.0;
    v.rest[static_cast<std::size_t>(k)] +=
        e.rest_volume_m3 / built.growth_rest_ratio[static_cast<std::size_t>(k)];
  }
  return v;
}

/// The next rest-volume ratios of the calibrated loads and the combination of the last solves
/// (coefficients of their differences from the newest, newest first) that they are.
struct CalibrationStep {
  Eigen::VectorXd ratios, combination;
};

/// The differences of the `q` solves before the newest from it, newest first (columns).
Eigen::MatrixXd differences(const std::vector<Eigen::VectorXd>& points, Eigen::Index q) {
  const std::size_t m = points.size() - 1;
  Eigen::MatrixXd d(points[m].size(), q);
  for (Eigen::Index i = 0; i < q; ++i)
    d.col(i) = points[m - 1 - static_cast<std::size_t>(i)] - points[m];
  return d;
}

/// Whether every ratio of `next` is finite and within half and twice the ratio it moves from.
bool plausible(const Eigen::VectorXd& next, const Eigen::VectorXd& ratio) {
  return next.allFinite() && (next.array() >= 0.5 * ratio.array()).all() &&
         (next.array() <= 2.0 * ratio.array()).all();
}

/// The reached ratios are about linear in the rest ratios, each load's in all of them (a region
/// shrinks as its neighbour grows). Once the solves span every load (the rest state among
/// them), the step that meets every prescription on the plane through the last ones; before,
/// or where that plane is singular or its step implausible, each load along the secant of its
/// own last two solves, with the step that assumes the rest ratio reached in full where that
/// secant's slope is not one the tissue around can give (the tets reaching more than twice
/// their own change).
CalibrationStep calibration_step(const GrowthCalibration& c, const Eigen::VectorXd& wanted) {
  const std::size_t m = c.ratios.size() - 1;
  const Eigen::VectorXd &ratio = c.ratios[m], &reached = c.reached[m];
  const auto n = ratio.size(), q = std::min<Eigen::Index>(n, static_cast<Eigen::Index>(m));
  const Eigen::MatrixXd dr = differences(c.ratios, q), dv = differences(c.reached, q);
  if (q == n) {
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(dv);
    if (lu.isInvertible()) {
      const Eigen::VectorXd combination = lu.solve(wanted - reached);
      const Eigen::VectorXd next = ratio + dr * combination;
      if (plausible(next, ratio)) return {next, combination};
    }
  }
  Eigen::VectorXd next(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    next[k] = ratio[k] * wanted[k] / reached[k];
    const double slope = dv(k, 0) / dr(k, 0);
    if (std::isfinite(slope) && slope > 0.0 && slope <= k_largest_growth_slope)
      next[k] = std::clamp(ratio[k] + (wanted[k] - reached[k]) / slope, 0.5 * ratio[k], 2.0 * ratio[k]);
  }
  return {next, dr.colPivHouseholderQr().solve(next - ratio)};
}

/// Fg of each rescaled tet: Q / s, weights times s^3 = the rescale of its volume; a group of tets
/// (deformation.volume: tet_groups) holding one is made again from its tets' Q and volumes
/// (F_g = sum_t V_t F_t / V_g) with its bulk weight in proportion to its volume.
void rescale_growth(const std::vector<double>& rescale, BodyModel& built) {
  ElasticModel& model = built.model;
  std::vector<char> changed(model.tets.size(), 0);
  for (std::size_t t = 0; t < built.growth_load_of_tet.size(); ++t) {
    const int k = built.growth_load_of_tet[t];
    if (k < 0 || rescale[static_cast<std::size_t>(k)] == 1.0) continue;
    const double f = rescale[static_cast<std::size_t>(k)];
    TetElement& e = model.tets[t];
    e.Q /= std::cbrt(f);
    e.rest_volume_m3 *= f;
    e.strain_weight *= f;
    e.volume_weight *= f;
    changed[t] = 1;
  }
  for (TetGroup& g : model.tet_groups) {
    if (std::none_of(g.tets.begin(), g.tets.end(),
                     [&](int t) { return changed[static_cast<std::size_t>(t)] != 0; }))
      continue;
    double volume = 0.0;
    for (int t : g.tets)
      volume += model.tets[static_cast<std::size_t>(t)].rest_volume_m3;
    g.weight *= volume / g.rest_volume_m3;
    g.rest_volume_m3 = volume;
    g.G.setZero();
    for (int t : g.tets) {
      const TetElement& e = model.tets[static_cast<std::size_t>(t)];
      for (int c = 0; c < 4; ++c) {
        const auto at =
            std::find(g.vertices.begin(), g.vertices.end(), e.vertices[static_cast<std::size_t>(c)]);
        g.G.row(at - g.vertices.begin()) += (e.rest_volume_m3 / volume) * e.Q.row(c);
      }
    }
  }
}

/// The largest combination coefficient the next solve's start takes from the last solves'
/// positions (a larger one extrapolates further than the solves say anything about).
constexpr double k_largest_start_coefficient = 4.0;

} // namespace

bool recalibrate_growth(const DeformationSettings& deformation, BodyModel& built, Eigen::MatrixX3d& p_m,
                        int round, bool rough, StageReport& report, GrowthCalibration& calibration) {
  const GrowthVolumes v = growth_volumes(built, p_m);
  // The calibrated loads: those with tets.
  std::vector<std::size_t> active;
  for (std::size_t k = 0; k < v.rest.size(); ++k)
    if (v.rest[k] > 0.0) active.push_back(k);
  const auto n = static_cast<Eigen::Index>(active.size());
  Eigen::VectorXd ratio(n), reached(n), wanted(n);
  bool met = true;
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t k = active[static_cast<std::size_t>(i)];
    const LoadSettings& load = deformation.loads[k];
    ratio[i] = built.growth_rest_ratio[k];
    reached[i] = v.deformed[k] / v.rest[k];
    wanted[i] = 1.0 + load.volume_change;
    if (std::abs(reached[i] - wanted[i]) <= (rough ? k_rough_growth_tolerance : k_growth_tolerance)) continue;
    met = false;
    if (round >= k_growth_rounds || !(reached[i] > 0.0)) {
      throw SettingError(growth_load_key(k, load),
                         "expected a volume change the tissue around can take up, found " +
                             format_number(100.0 * load.volume_change) + " % for " + growth_target(load) +
                             ", which reaches " + format_number(100.0 * (reached[i] - 1.0)) + " % after " +
                             std::to_string(round + 1) +
                             " solves (no room to give way: a softer or more compressible tissue around it, "
                             "or a smaller change)");
    }
  }
  // Met on a rough solve: the same rest volumes solved exactly, to be measured again (this
  // solve's point is left out: the next one has the same ratios).
  if (met && rough) return true;
  if (met) {
    for (const std::size_t k : active)
      report.modelled.push_back("growth of " + growth_target(deformation.loads[k]) +
                                ": its tets' volume changed by " +
                                format_number(100.0 * (v.deformed[k] / v.rest[k] - 1.0)) +
                                " % as prescribed, from a rest-volume change of " +
                                format_number(100.0 * (built.growth_rest_ratio[k] - 1.0)) + " % (" +
                                std::to_string(round + 1) + " solves)");
    return false;
  }
  if (calibration.ratios.empty()) { // no growth reaches no change, at rest
    calibration.ratios.push_back(Eigen::VectorXd::Ones(n));
    calibration.reached.push_back(Eigen::VectorXd::Ones(n));
    calibration.positions_m.push_back(built.model.rest_positions_m);
  }
  calibration.ratios.push_back(ratio);
  calibration.reached.push_back(reached);
  calibration.positions_m.push_back(p_m);
  const CalibrationStep step = calibration_step(calibration, wanted);
  std::vector<double> rescale(built.growth_rest_ratio.size(), 1.0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::size_t k = active[static_cast<std::size_t>(i)];
    rescale[k] = step.ratios[i] / ratio[i];
    built.growth_rest_ratio[k] = step.ratios[i];
  }
  rescale_growth(rescale, built);
  // The next solve starts where the same combination of the last solves' positions is: about
  // its result, as the volumes are about linear in the rest ratios.
  if (step.combination.allFinite() && step.combination.cwiseAbs().maxCoeff() <= k_largest_start_coefficient) {
    const std::size_t m = calibration.positions_m.size() - 1;
    for (Eigen::Index i = 0; i < step.combination.size(); ++i)
      p_m += step.combination[i] *
             (calibration.positions_m[m - 1 - static_cast<std::size_t>(i)] - calibration.positions_m[m]);
  }
  return true;
}

DeformationSettings rough_solve_settings(const DeformationSettings& deformation, const ElasticModel& model,
                                         const Eigen::MatrixX3d& p_m, const GrowthCalibration& calibration) {
  DeformationSettings settings = deformation;
  const double start = free_gradient_norm(model, model_gradient(model, StepInertia{}, p_m));
  const double target = deformation.solver.relative_residual_tolerance * calibration.first_residual_N;
  if (start > 0.0 && target > 0.0)
    settings.solver.relative_residual_tolerance = std::min(1.0, target / start);
  return settings;
}

void report_growth(const DeformationSettings& deformation, const std::vector<std::size_t>& grown_tets,
                   StageReport& report) {
  for (std::size_t k = 0; k < deformation.loads.size(); ++k) {
    const LoadSettings& load = deformation.loads[k];
    if (!load_type(load.kind).changes_rest_volume) continue;
    if (k >= grown_tets.size() || grown_tets[k] == 0) {
      throw SettingError(growth_load_key(k, load),
                         load.regions.empty()
                             ? "expected an organ with tets of its own in a simulated solid body, found '" +
                                   load.organ + "' (a surface organ, or one meshed with the organ holding it)"
                             : "expected regions holding the centroid of some tet of a simulated solid body, "
                               "found " +
                                   growth_target(load) + " holding none (a region smaller than the tets?)");
    }
    report.modelled.push_back("growth of " + growth_target(load) + ": rest volume of its " +
                              std::to_string(grown_tets[k]) + " tets changed by " +
                              format_number(100.0 * load.volume_change) +
                              " % (F = Fe Fg, Fg = (1 + g)^(1/3) I; the tissue around answers elastically)");
  }
}

double growth_displacement_m(const LoadSettings& load, const Eigen::MatrixX3d& organ_rest_mm) {
  if (organ_rest_mm.rows() == 0) return 0.0;
  const Eigen::RowVector3d centre = organ_rest_mm.colwise().mean();
  const double extent_mm = (organ_rest_mm.rowwise() - centre).rowwise().norm().maxCoeff();
  return k_mm * extent_mm * std::abs(std::cbrt(1.0 + load.volume_change) - 1.0);
}

} // namespace phantasm::sim_detail
