#include "anatomy/anatomy_plan.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <sstream>

namespace phantasm {

bool WorldBox::intersects(const WorldBox& other) const {
  return (min_mm.array() <= other.max_mm.array()).all() && (other.min_mm.array() <= max_mm.array()).all();
}

std::optional<WorldBox> analytic_shape_bounds(const ShapeSettings& shape) {
  if (shape.kind == ShapeKind::mesh || shape.kind == ShapeKind::label_volume) return std::nullopt;
  constexpr double degree = M_PI / 180.0;
  const Eigen::Matrix3d rotation =
      (Eigen::AngleAxisd(shape.rotation_deg.z() * degree, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(shape.rotation_deg.y() * degree, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(shape.rotation_deg.x() * degree, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Eigen::Vector3d half_extent;
  if (shape.kind == ShapeKind::ellipsoid) {
    // The support function of an ellipsoid R diag(r) S^2 along axis e is |diag(r) R^T e|.
    for (int a = 0; a < 3; ++a) {
      half_extent[a] = (shape.radii_mm.asDiagonal() * rotation.row(a).transpose()).norm();
    }
  } else if (shape.kind == ShapeKind::superquadric) {
    // A superquadric lies inside its box of radii; bound the rotated box.
    half_extent = rotation.cwiseAbs() * shape.radii_mm;
  } else {
    half_extent = rotation.cwiseAbs() * (0.5 * shape.size_mm);
  }
  return WorldBox{shape.center_mm - half_extent, shape.center_mm + half_extent};
}

int nesting_depth(const Scene& scene, const OrganSettings& organ) {
  int depth = 0;
  const OrganSettings* current = &organ;
  // Validation guarantees the nesting has no cycles; the bound is a second guard.
  while (!current->inside.empty() && depth <= static_cast<int>(scene.anatomy.organs.size())) {
    current = scene.find_organ(current->inside);
    if (current == nullptr) break;
    ++depth;
  }
  return depth;
}

StageReport plan_anatomy(const Scene& scene) {
  StageReport report;
  report.stage = "anatomy";
  const AnatomySettings& anatomy = scene.anatomy;
  for (const auto& organ : anatomy.organs) {
    std::ostringstream line;
    line << organ.name << ": " << to_string(organ.shape.kind) << " surface of " << anatomy.base_mesh_triangles
         << " base triangles with fitted patches, tissue " << organ.tissue;
    if (!organ.inside.empty())
      line << ", inside " << organ.inside << " (depth " << nesting_depth(scene, organ) << ")";
    line << (organ.solid ? ", solid (tetrahedral interior)" : ", surface only (no interior mesh)");
    report.modelled.push_back(line.str());
  }
  if (anatomy.variation > 0.0) {
    std::ostringstream line;
    line << "organ sizes varied by up to " << 100.0 * anatomy.variation << " % from seed " << scene.seed;
    report.modelled.push_back(line.str());
  } else {
    report.skipped.push_back("seeded size variation (anatomy.variation is 0)");
  }
  return report;
}

} // namespace phantasm
