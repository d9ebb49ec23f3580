// Growth and atrophy: a change of rest volume of an organ's tets (multiplicative growth,
// F = Fe Fg), which the surrounding tissue answers mechanically. Internal to sim.
#pragma once

#include "core/stage_report.hpp"
#include "sim/elastic_model.hpp"
#include "sim/sim_settings.hpp"

#include <cstddef>
#include <vector>

namespace phantasm::sim_detail {

/// Applies every growth load of `loads` to the tets of one body, appended to `model` from
/// `first_tet` with `organ_of_tet` (organ table indices) for each: a tet of a grown organ gets
/// Fg = (1 + g)^(1/3) I, so its elastic energy reads Fe = F Fg^-1 (Q / (1 + g)^(1/3)) and its
/// weights are those of its grown rest volume V (1 + g). Counts the tets grown per load into
/// `grown_tets` (one entry per load).
/// @throws SettingError (deformation.volume) for growth with vertex_stars, whose bulk term is
///   not per tet
void apply_growth(const DeformationSettings& deformation, const OrganTable& organs,
                  const std::vector<std::size_t>& organ_of_tet, std::size_t first_tet, ElasticModel& model,
                  std::vector<std::size_t>& grown_tets);

/// Checks that every growth load grew some tets and reports each one as modelled.
/// @throws SettingError (deformation.loads[k].organ) for an organ no simulated tet lies in
void report_growth(const DeformationSettings& deformation, const std::vector<std::size_t>& grown_tets,
                   StageReport& report);

/// The largest distance (m) a growth load moves the rest surface of its organ, about: the
/// organ's extent times |(1 + g)^(1/3) - 1| (the scale of the residual test's force).
double growth_displacement_m(const LoadSettings& load, const Eigen::MatrixX3d& organ_rest_mm);

} // namespace phantasm::sim_detail
