#include "pipeline/anatomy_checks.hpp"

#include "anatomy/shape_source.hpp"
#include "core/error.hpp"
#include "core/format.hpp"

#include <algorithm>
#include <string>

namespace phantasm {
namespace {

/// The extent of an organ's closed surface along each axis, mm; none without one.
std::optional<Eigen::Vector3d> extent(const Organ& organ) {
  if (!organ.surface || organ.surface->base_mesh().vertices.rows() == 0) return std::nullopt;
  const Eigen::MatrixX3d& v = organ.surface->base_mesh().vertices;
  return (v.colwise().maxCoeff() - v.colwise().minCoeff()).transpose();
}

bool inside_obstacle(const ObstacleSettings& o, const Eigen::Vector3d& x) {
  if (o.shape == ObstacleShape::sphere) return (x - o.point_mm).norm() < o.radius_mm;
  return (x - o.point_mm).dot(o.normal) < 0.0; // the normal points out of it, towards the tissue
}

/// An organ read from a mesh file larger than its container. Only shapes whose source says so
/// (NestingCheck::when_built: mesh files) are checked here: analytic shapes are checked by the
/// scene's validation, and an organ from a label volume nests by construction (its surface bounds
/// its labels united with those inside it), where a fitted surface's base mesh may reach a few
/// millimetres beyond its container's without any error of the scene's.
void check_nesting(const Scene& scene, const Phantom& phantom) {
  for (std::size_t i = 0; i < phantom.organs.size(); ++i) {
    const Organ& organ = phantom.organs[i];
    if (organ.inside.empty()) continue;
    const std::vector<OrganSettings>& declared = scene.anatomy.organs;
    const auto settings = std::find_if(declared.begin(), declared.end(),
                                       [&](const OrganSettings& o) { return o.name == organ.name; });
    if (settings == declared.end() || shape_source(settings->shape.kind).nesting != NestingCheck::when_built)
      continue;
    const Organ* container = phantom.find(organ.inside);
    if (container == nullptr) continue;
    const std::optional<Eigen::Vector3d> size = extent(organ), room = extent(*container);
    if (!size || !room) continue;
    for (int a = 0; a < 3; ++a) {
      if ((*size)[a] > 1.05 * (*room)[a]) {
        const std::string key = "anatomy.organs[" + std::to_string(settings - declared.begin()) + "].inside";
        throw SettingError(key, std::string("expected a container at least as large as the organ it holds, "
                                            "found '") +
                                    container->name + "' " + format_number((*room)[a]) + " mm across along " +
                                    "xyz"[a] + " and '" + organ.name + "' " + format_number((*size)[a]) +
                                    " mm");
      }
    }
  }
}

void check_obstacles(const Scene& scene, const Phantom& phantom) {
  const std::vector<ObstacleSettings>& obstacles = scene.deformation.obstacles;
  if (obstacles.empty() || scene.deformation.mode == DeformationMode::none) return;
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    const Eigen::MatrixX3d& v = organ.surface->base_mesh().vertices;
    if (v.rows() == 0) continue;
    std::size_t first = obstacles.size(); // the obstacle holding the first vertex
    bool enclosed = true;
    for (Eigen::Index r = 0; r < v.rows() && enclosed; ++r) {
      const Eigen::Vector3d x = v.row(r).transpose();
      bool in = false;
      for (std::size_t k = 0; k < obstacles.size() && !in; ++k) {
        if (inside_obstacle(obstacles[k], x)) {
          in = true;
          if (first == obstacles.size()) first = k;
        }
      }
      enclosed = in;
    }
    if (enclosed) {
      throw SettingError("deformation.obstacles[" + std::to_string(first) + "]",
                         "expected obstacles beside the tissue at rest (no simulated vertex may enter one), "
                         "found organ '" +
                             organ.name + "' wholly inside " +
                             (obstacles.size() > 1 ? "the obstacles" : "the obstacle"));
    }
  }
}

} // namespace

void check_built_anatomy(const Scene& scene, const Phantom& phantom) {
  check_nesting(scene, phantom);
  check_obstacles(scene, phantom);
}

} // namespace phantasm
