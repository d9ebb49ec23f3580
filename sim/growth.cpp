// Growth and atrophy as a change of the tets' rest volume: Fg = (1 + g)^(1/3) I per grown tet.
#include "sim/growth.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "sim/body_embedding.hpp"

#include <cmath>
#include <string>

namespace phantasm::sim_detail {
namespace {

std::string organ_key(std::size_t k) {
  return "deformation.loads[" + std::to_string(k) + "].organ";
}

} // namespace

void apply_growth(const DeformationSettings& deformation, const OrganTable& organs,
                  const std::vector<std::size_t>& organ_of_tet, std::size_t first_tet, ElasticModel& model,
                  std::vector<std::size_t>& grown_tets) {
  grown_tets.resize(deformation.loads.size(), 0);
  for (std::size_t k = 0; k < deformation.loads.size(); ++k) {
    const LoadSettings& load = deformation.loads[k];
    if (load.kind != LoadKind::growth) continue;
    if (deformation.volume == VolumeFormulation::vertex_star) {
      throw SettingError("deformation.volume",
                         "expected per_tet or tet_groups with a growth load (a vertex star's bulk term "
                         "spans organs), found 'vertex_stars'");
    }
    const int organ = organs.index_of(load.organ);
    if (organ < 0) continue; // no tet carries it: report_growth says so
    // Fe = F Fg^-1 = X Q / s: the tet's elastic terms read Q / s, and they weigh the grown
    // rest volume V s^3 = V (1 + g) (energy per unit of grown volume).
    const double volume_ratio = 1.0 + load.volume_change;
    const double s = std::cbrt(volume_ratio);
    for (std::size_t t = 0; t < organ_of_tet.size(); ++t) {
      if (organ_of_tet[t] != static_cast<std::size_t>(organ)) continue;
      TetElement& e = model.tets[first_tet + t];
      e.Q /= s;
      e.rest_volume_m3 *= volume_ratio;
      e.strain_weight *= volume_ratio;
      e.volume_weight *= volume_ratio;
      ++grown_tets[k];
    }
  }
}

void report_growth(const DeformationSettings& deformation, const std::vector<std::size_t>& grown_tets,
                   StageReport& report) {
  for (std::size_t k = 0; k < deformation.loads.size(); ++k) {
    const LoadSettings& load = deformation.loads[k];
    if (load.kind != LoadKind::growth) continue;
    if (k >= grown_tets.size() || grown_tets[k] == 0) {
      throw SettingError(organ_key(k),
                         "expected an organ with tets of its own in a simulated solid body, found '" +
                             load.organ + "' (a surface organ, or one meshed with the organ holding it)");
    }
    report.modelled.push_back("growth of " + load.organ + ": rest volume of its " +
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
