#pragma once

// What the deformation tests share: a scene of the repository loaded (failing the test with its
// problems when it does not load), and the signed volume of one tet of a deformed body's rest or
// deformed vertices.

#include "core/error.hpp"
#include "geometry/tet_quality.hpp"
#include "scene/scene.hpp"
#include "sim/phantom_deformation.hpp"

#include <gtest/gtest.h>

#include <map>
#include <string>

namespace phantasm::testing {

/// The scene at `path` (relative to the repository root).
inline Scene load_repository_scene(const std::string& path) {
  SceneLoadResult result = load_scene(std::string(PHANTASM_SOURCE_DIR) + "/" + path);
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
  return *result.scene;
}

/// Signed volume of tet t of `tets` over the vertices x (rows), mm^3.
inline double body_tet_volume(const Eigen::MatrixX3d& x, const Eigen::MatrixX4i& tets, Eigen::Index t) {
  return signed_volume(x.row(tets(t, 0)).transpose(), x.row(tets(t, 1)).transpose(),
                       x.row(tets(t, 2)).transpose(), x.row(tets(t, 3)).transpose());
}

/// Per organ name, the deformed volume of its tets (in every solved body) over their rest volume,
/// minus 1: the volume change each organ reached.
inline std::map<std::string, double> organ_volume_changes(const PhantomDeformation& d,
                                                          const OrganTable& organs) {
  std::map<std::string, double> rest, deformed, change;
  for (const DeformedBody& body : d.bodies)
    for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
      const std::string& name =
          organs[static_cast<std::size_t>(body.tet_organ[static_cast<std::size_t>(t)])].name;
      rest[name] += body_tet_volume(body.rest_mm, body.tets, t);
      deformed[name] += body_tet_volume(body.deformed_mm, body.tets, t);
    }
  for (const auto& [name, volume] : rest)
    change[name] = deformed[name] / volume - 1.0;
  return change;
}

} // namespace phantasm::testing
