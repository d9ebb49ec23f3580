// Landmarks are material points of the organ they name: the deepest point of its own material
// lies inside it and outside every organ nested in it, in both states, and moves with that
// material; the extreme points are its own surface vertices.

#include "anatomy/mesh_distance.hpp"
#include "anatomy/phantom.hpp"
#include "core/format.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

namespace {

Scene load(const std::string& path) {
  SceneLoadResult result = load_scene(std::string(PHANTASM_SOURCE_DIR) + "/" + path);
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
  return *result.scene;
}

/// Signed distances to an organ's surface and to each organ nested in it, in one state: the
/// clearance of x in the organ's own material (mm; positive inside it, outside the nested ones).
double clearance(const Phantom& phantom, const std::string& organ, const Eigen::Vector3d& x) {
  const Organ& own = *phantom.find(organ);
  double c = -MeshDistance(own.surface->tessellate(0.25)).signed_distance(x);
  for (const Organ& nested : phantom.organs)
    if (nested.inside == organ && nested.surface)
      c = std::min(c, MeshDistance(nested.surface->tessellate(0.25)).signed_distance(x));
  return c;
}

} // namespace

TEST(OrganLandmarks, DeepestPointsLieInTheirOrgansOwnMaterialInBothStates) {
  const Scene scene = load("tests/data/scenes/small-head.yaml");
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  const Phantom moved = deformed_phantom(phantom, d);
  const DeformationMap map(d.bodies, 4.0);
  const std::vector<Landmark> landmarks = organ_landmarks(phantom, &d, &map);
  ASSERT_EQ(landmarks.size(), 7u * phantom.organs.size());
  double moved_most = 0.0;
  for (const Landmark& l : landmarks) {
    SCOPED_TRACE(l.name);
    const Organ& organ = *phantom.find(l.organ);
    const std::size_t o = static_cast<std::size_t>(&organ - phantom.organs.data());
    if (l.name == l.organ + "_deepest") {
      // Well inside: the scalp's shell is about 6 mm thick, its deepest point about 3 mm from both sides.
      EXPECT_GT(clearance(phantom, l.organ, l.reference_mm), 2.0);
      EXPECT_GT(clearance(moved, l.organ, l.deformed_mm), 2.0);
      if (d.organs[o].moved_by == "fixed") {
        EXPECT_EQ(l.deformed_mm, l.reference_mm);
      }
      if (d.organs[o].moved_by == "solver") {
        bool exact = false;
        EXPECT_EQ(l.deformed_mm, map.forward(l.reference_mm, &exact));
        EXPECT_TRUE(exact);
      }
      moved_most = std::max(moved_most, (l.deformed_mm - l.reference_mm).norm());
    } else {
      // An extreme point is one of the organ's own surface vertices, in both states.
      const Eigen::MatrixX3d& rest = organ.surface->rest_positions();
      Eigen::Index v = 0;
      (rest.rowwise() - l.reference_mm.transpose()).rowwise().norm().minCoeff(&v);
      EXPECT_EQ(rest.row(v).transpose(), l.reference_mm);
      EXPECT_EQ(d.organs[o].surface_mm.row(v).transpose(), l.deformed_mm);
    }
  }
  EXPECT_GT(moved_most, 0.0); // the grey matter's deepest point moves with the push
}
