#pragma once

#include "core/stage_report.hpp"
#include "scene/scene.hpp"

#include <Eigen/Core>

#include <optional>

namespace phantasm {

/// An axis-aligned box in world space (RAS mm).
struct WorldBox {
  Eigen::Vector3d min_mm;
  Eigen::Vector3d max_mm;

  bool intersects(const WorldBox& other) const;
};

/// The world-space bounding box of an analytic shape (ellipsoid, superquadric), or nothing for
/// shapes whose extent is known only once their file is read (meshes, label volumes).
std::optional<WorldBox> analytic_shape_bounds(const ShapeSettings& shape);

/// How deep an organ is nested: 0 for an outermost organ, 1 for an organ inside it, ...
int nesting_depth(const Scene& scene, const OrganSettings& organ);

/// What the anatomy stage will build for this scene: one patch surface per organ, a tet mesh
/// for each solid organ, and the nesting that decides which tissue fills a point.
StageReport plan_anatomy(const Scene& scene);

} // namespace phantasm
