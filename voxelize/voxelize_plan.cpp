#include "voxelize/voxelize_plan.hpp"

#include <sstream>

namespace phantasm {
namespace {

WorldBox field_of_view_box(const ImageGrid& grid) {
  // The field of view covers the voxels' full extent, half a voxel beyond the outer centres.
  WorldBox box{Eigen::Vector3d::Constant(1e300), Eigen::Vector3d::Constant(-1e300)};
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d ijk;
    for (int a = 0; a < 3; ++a)
      ijk[a] = (corner >> a) & 1 ? grid.dims[a] - 0.5 : -0.5;
    const Eigen::Vector3d p = grid.world_from_index(ijk);
    box.min_mm = box.min_mm.cwiseMin(p);
    box.max_mm = box.max_mm.cwiseMax(p);
  }
  return box;
}

} // namespace

bool organ_in_field_of_view(const std::optional<WorldBox>& bounds, const ImageGrid& grid) {
  return !bounds || bounds->intersects(field_of_view_box(grid));
}

StageReport plan_voxelize(const VoxelizationSettings& settings, const OrganTable& organs,
                          const GridSettings& grid_settings) {
  StageReport report;
  report.stage = "voxelize";
  const ImageGrid grid = grid_settings.grid();
  std::ostringstream line;
  line << "grid " << grid.dims.x() << " x " << grid.dims.y() << " x " << grid.dims.z() << " voxels of "
       << grid.spacing_mm.x() << " x " << grid.spacing_mm.y() << " x " << grid.spacing_mm.z() << " mm, "
       << grid_settings.orientation << ", narrow-band level sets until dense output";
  report.modelled.push_back(line.str());
  for (std::size_t i = 0; i < organs.size(); ++i) {
    const OrganEntry& organ = organs[i];
    const auto bounds =
        i < settings.organ_bounds_mm.size() ? settings.organ_bounds_mm[i] : std::optional<WorldBox>();
    if (organ_in_field_of_view(bounds, grid)) {
      report.modelled.push_back(organ.name + ": level set, reference and deformed");
      // An organ smaller than a voxel may fill none: its label never shows (#20, warnings).
      const double voxel = grid.spacing_mm.minCoeff();
      if (bounds && (bounds->max_mm - bounds->min_mm).maxCoeff() < voxel) {
        std::ostringstream warning;
        warning << organ.name << ": spans at most " << (bounds->max_mm - bounds->min_mm).maxCoeff()
                << " mm, less than a voxel (" << voxel
                << " mm): it may fill no voxel of the labels; expected a finer grid.voxel_size_mm or a "
                   "larger organ";
        report.warnings.push_back(warning.str());
      }
    } else {
      report.skipped.push_back(organ.name + ": outside the field of view");
      report.warnings.push_back(
          organ.name + ": outside the field of view at rest, so no voxel shows it; expected it inside "
                       "grid.field_of_view_mm about grid.center_mm");
    }
  }
  const VoxelizationSettings& o = settings;
  const bool deformed = settings.deformed;
  auto want = [&](bool asked, const std::string& what, const std::string& why_not) {
    if (asked) {
      report.modelled.push_back(what);
    } else {
      report.skipped.push_back(what + " (" + why_not + ")");
    }
  };
  want(o.labels, "label maps", "outputs.labels is false");
  std::ostringstream fractions;
  fractions << "partial-volume fractions, " << settings.supersampling << "^3 samples per voxel";
  want(o.fractions, fractions.str(), "neither outputs.fractions nor outputs.images asks for them");
  want(o.displacement_fields && deformed, "displacement fields both ways",
       deformed ? "outputs.displacement_fields is false" : "nothing deforms");
  want(o.jacobian && deformed, "Jacobian determinant map",
       deformed ? "outputs.jacobian is false" : "nothing deforms");
  want(o.landmarks, "anatomical landmarks", "outputs.landmarks is false");
  want(o.keep_level_sets, ".vdb grids", "outputs.vdb is false");
  return report;
}

} // namespace phantasm
