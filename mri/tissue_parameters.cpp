#include "mri/tissue_parameters.hpp"

#include "core/tissue_table.hpp"

#include <vector>

namespace phantasm {
namespace {

void take(std::optional<double>& value, std::string& source, const std::optional<double>& candidate,
          const std::string& candidate_source) {
  if (!value && candidate) {
    value = candidate;
    source = candidate_source;
  }
}

} // namespace

std::map<std::string, TissueParameters> resolve_tissue_parameters(const MriSettings& settings,
                                                                  const OrganTable& organs) {
  std::map<std::string, TissueParameters> resolved;
  // The organs' tissues, then those the tissue regions give.
  std::vector<std::string> tissues;
  for (const OrganEntry& organ : organs)
    tissues.push_back(organ.tissue);
  for (const TissueRegionSettings& region : settings.regions)
    tissues.push_back(region.tissue);
  for (const std::string& tissue : tissues) {
    if (resolved.count(tissue) != 0) continue;
    TissueParameters p;
    p.tissue = tissue;
    for (const auto& o : settings.tissues) {
      if (o.tissue != tissue) continue;
      take(p.T1_ms, p.T1_source, o.T1_ms, "scene");
      take(p.T2_ms, p.T2_source, o.T2_ms, "scene");
      take(p.T2star_ms, p.T2star_source, o.T2star_ms, "scene");
      take(p.PD, p.PD_source, o.PD, "scene");
    }
    if (const TissueRecord* r = TissueTable::builtin().find(tissue, settings.field_strength_T)) {
      take(p.T1_ms, p.T1_source, r->T1_ms, r->T1_source);
      take(p.T2_ms, p.T2_source, r->T2_ms, r->T2_source);
      take(p.T2star_ms, p.T2star_source, r->T2star_ms, r->T2star_source);
      take(p.PD, p.PD_source, r->PD, r->PD_source);
    }
    resolved[tissue] = p;
  }
  return resolved;
}

Relaxation relaxation_of(const TissueParameters& p) {
  return Relaxation{p.PD.value_or(0.0), p.T1_ms.value_or(1.0), p.T2_ms.value_or(0.0),
                    p.T2star_ms.value_or(p.T2_ms.value_or(0.0))};
}

} // namespace phantasm
