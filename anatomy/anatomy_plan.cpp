#include "anatomy/anatomy_plan.hpp"

#include <sstream>

namespace phantasm {

StageReport plan_anatomy(const AnatomySettings& anatomy, const OrganTable& organs) {
  StageReport report;
  report.stage = "anatomy";
  for (std::size_t i = 0; i < anatomy.organs.size(); ++i) {
    const OrganSettings& organ = anatomy.organs[i];
    std::ostringstream line;
    line << organ.name << ": " << to_string(organ.shape.kind) << " surface of " << anatomy.base_mesh_triangles
         << " base triangles with fitted patches, tissue " << organ.tissue;
    if (!organ.inside.empty()) line << ", inside " << organ.inside << " (depth " << organs[i].depth << ")";
    line << (organ.solid ? ", solid (tetrahedral interior)" : ", surface only (no interior mesh)");
    report.modelled.push_back(line.str());
  }
  if (anatomy.variation > 0.0) {
    std::ostringstream line;
    line << "organ sizes varied by up to " << 100.0 * anatomy.variation << " % from seed " << anatomy.seed;
    report.modelled.push_back(line.str());
  } else {
    report.skipped.push_back("seeded size variation (anatomy.variation is 0)");
  }
  return report;
}

} // namespace phantasm
