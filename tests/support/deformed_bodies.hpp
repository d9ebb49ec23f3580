#pragma once

// What the deformation tests share: a scene of the repository loaded (failing the test with its
// problems when it does not load), and the signed volume of one tet of a deformed body's rest or
// deformed vertices.

#include "core/error.hpp"
#include "geometry/tet_quality.hpp"
#include "scene/scene.hpp"

#include <gtest/gtest.h>

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

} // namespace phantasm::testing
