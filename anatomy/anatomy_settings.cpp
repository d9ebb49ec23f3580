#include "anatomy/anatomy_settings.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace phantasm {

OrganTable organ_table(const AnatomySettings& anatomy) {
  std::vector<OrganNesting> organs;
  organs.reserve(anatomy.organs.size());
  for (const OrganSettings& organ : anatomy.organs)
    organs.push_back({organ.name, organ.tissue, organ.inside});
  return OrganTable(organs);
}

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

const char* to_string(TetInterfaces interfaces) {
  return interfaces == TetInterfaces::materials ? "materials" : "organs";
}

const char* to_string(ShapeKind kind) {
  switch (kind) {
  case ShapeKind::ellipsoid: return "ellipsoid";
  case ShapeKind::superquadric: return "superquadric";
  case ShapeKind::box: return "box";
  case ShapeKind::sheet: return "sheet";
  case ShapeKind::mesh: return "mesh";
  case ShapeKind::label_volume: return "label_volume";
  }
  return "?";
}

} // namespace phantasm
