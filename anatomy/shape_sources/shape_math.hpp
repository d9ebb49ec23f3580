// What several shape sources share: their common scene keys, the rotation of an analytic shape,
// and the bounds of a rotated box. Internal to the shape sources.
#pragma once

#include "anatomy/shape_source.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace phantasm::shape_math {

constexpr double k_infinity = std::numeric_limits<double>::infinity();

/// `center_mm`: the shape's centre, RAS mm, required.
inline ShapeParameter center() {
  ShapeParameter p{"center_mm", ShapeParameter::Kind::vector3, &ShapeSettings::center_mm};
  p.min = -1e5;
  p.max = 1e5;
  p.unit = "mm";
  p.required = true;
  return p;
}

/// `rotation_deg`: rotations about x, then y, then z, degrees; optional.
inline ShapeParameter rotation() {
  ShapeParameter p{"rotation_deg", ShapeParameter::Kind::vector3, &ShapeSettings::rotation_deg};
  p.min = -360.0;
  p.max = 360.0;
  p.unit = "degrees";
  return p;
}

/// A required vector of lengths greater than 0 mm (radii, sizes).
inline ShapeParameter lengths(const char* key, Eigen::Vector3d ShapeSettings::*member,
                              ShapeParameter::Kind kind = ShapeParameter::Kind::vector3) {
  ShapeParameter p{key, kind, member};
  p.min = 0.0;
  p.min_exclusive = true;
  p.max = k_infinity;
  p.unit = "mm";
  p.required = true;
  return p;
}

/// `radii_mm`: semi-axes before rotation, mm, required; one number for all three allowed.
inline ShapeParameter radii() {
  ShapeParameter p = lengths("radii_mm", &ShapeSettings::radii_mm);
  p.scalar_allowed = true;
  return p;
}

/// `cells`: the structured mesh's cells along `axes` axes, required.
inline ShapeParameter cells(int axes) {
  ShapeParameter p{"cells", ShapeParameter::Kind::cells};
  p.axes = axes;
  p.required = true;
  return p;
}

/// The rotation of an analytic shape: about x, then y, then z.
inline Eigen::Matrix3d rotation_matrix(const Eigen::Vector3d& rotation_deg) {
  constexpr double degree = M_PI / 180.0;
  return (Eigen::AngleAxisd(rotation_deg.z() * degree, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rotation_deg.y() * degree, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rotation_deg.x() * degree, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// The bounds of the box of half extents `half_box` about the shape's centre, rotated as the
/// shape is.
inline WorldBox rotated_box_bounds(const ShapeSettings& shape, const Eigen::Vector3d& half_box) {
  const Eigen::Vector3d half_extent = rotation_matrix(shape.rotation_deg).cwiseAbs() * half_box;
  return WorldBox{shape.center_mm - half_extent, shape.center_mm + half_extent};
}

} // namespace phantasm::shape_math
