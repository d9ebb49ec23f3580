#include "mri/tissue_parameters.hpp"

#include "core/tissue_table.hpp"

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
  for (const OrganEntry& organ : organs) {
    if (resolved.count(organ.tissue) != 0) continue;
    TissueParameters p;
    p.tissue = organ.tissue;
    for (const auto& o : settings.tissues) {
      if (o.tissue != organ.tissue) continue;
      take(p.T1_ms, p.T1_source, o.T1_ms, "scene");
      take(p.T2_ms, p.T2_source, o.T2_ms, "scene");
      take(p.T2star_ms, p.T2star_source, o.T2star_ms, "scene");
      take(p.PD, p.PD_source, o.PD, "scene");
    }
    if (const TissueRecord* r = TissueTable::builtin().find(organ.tissue, settings.field_strength_T)) {
      take(p.T1_ms, p.T1_source, r->T1_ms, r->T1_source);
      take(p.T2_ms, p.T2_source, r->T2_ms, r->T2_source);
      take(p.T2star_ms, p.T2star_source, r->T2star_ms, r->T2star_source);
      take(p.PD, p.PD_source, r->PD, r->PD_source);
    }
    resolved[organ.tissue] = p;
  }
  return resolved;
}

} // namespace phantasm
