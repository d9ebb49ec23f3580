#include "anatomy/anatomy_plan.hpp"

#include "anatomy/shape_source.hpp"
#include "anatomy/tet_mesh.hpp"
#include "core/format.hpp"

#include <sstream>

namespace phantasm {

StageReport plan_anatomy(const AnatomySettings& anatomy, const OrganTable& organs) {
  StageReport report;
  report.stage = "anatomy";
  for (std::size_t i = 0; i < anatomy.organs.size(); ++i) {
    const OrganSettings& organ = anatomy.organs[i];
    // The organ's own base size when it sets one (the run builds that, not the scene's).
    const bool own = organ.base_mesh_triangles > 0;
    const int base = own ? organ.base_mesh_triangles : anatomy.base_mesh_triangles;
    std::ostringstream line;
    line << organ.name << ": " << to_string(organ.shape.kind) << " surface of " << base << " base triangles"
         << (own ? " (its own base_mesh_triangles)" : "") << " with fitted patches, tissue " << organ.tissue;
    if (!organ.inside.empty()) line << ", inside " << organ.inside << " (depth " << organs[i].depth << ")";
    if (!organ.solid) {
      line << ", surface only (no interior mesh)";
    } else if (const ShapeSource& source = shape_source(organ.shape.kind); source.plan_tet_size) {
      // Its tets' size follows from the base size (anatomy/tet_mesh.hpp, criteria_for_boundary_size)
      // and the surface area.
      const double area = source.area_volume(organ.shape).first;
      line << ", solid (tetrahedral interior, tets of about "
           << format_number(criteria_for_boundary_size(area, base).cell_size_mm) << " mm)";
    } else {
      line << ", solid (tetrahedral interior, its boundary of about the base size)";
    }
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
