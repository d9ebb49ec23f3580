// Growth and atrophy (deformation loads of type growth): the prescribed change of each organ's
// rest volume, solved with the tissue around it answering, measured on the deformed tets.

#include "core/error.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/support/deformed_bodies.hpp"

#include <gtest/gtest.h>

#include <map>

using namespace phantasm;

using phantasm::testing::organ_volume_changes;

// One ball shrinks by 10 %, the other grows by 5 %: each ends within 1 % (absolute) of its
// prescription, the compliant layer around them takes up the difference, nothing inverts.
TEST(Growth, EachOrgansVolumeChangesAsPrescribedAndTheLayerAroundAnswers) {
  const Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/growth-balls.yaml");
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(report.status, "done");
  ASSERT_EQ(d.bodies.size(), 1u); // the layer, carrying both balls
  EXPECT_EQ(d.bodies[0].inverted_tets, 0);
  const std::map<std::string, double> change = organ_volume_changes(d, scene.organs);
  ASSERT_EQ(change.count("left"), 1u);
  ASSERT_EQ(change.count("right"), 1u);
  EXPECT_NEAR(change.at("left"), -0.10, 0.01);
  EXPECT_NEAR(change.at("right"), 0.05, 0.01);
  // The layer's boundary is held by the box: the volume it gives the balls is its own.
  double rest_total = 0.0, deformed_total = 0.0;
  for (Eigen::Index t = 0; t < d.bodies[0].tets.rows(); ++t) {
    rest_total += phantasm::testing::body_tet_volume(d.bodies[0].rest_mm, d.bodies[0].tets, t);
    deformed_total += phantasm::testing::body_tet_volume(d.bodies[0].deformed_mm, d.bodies[0].tets, t);
  }
  EXPECT_NEAR(deformed_total / rest_total, 1.0, 1e-6);
  EXPECT_GT(change.at("layer"), 0.0)
      << "the layer takes up what the shrinking ball loses, net of the growing one";
}

// Growth with the bulk term on vertex stars (which span organs) is a clear error at the key.
TEST(Growth, WithVertexStarsIsAClearError) {
  Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/growth-balls.yaml");
  scene.deformation.volume = VolumeFormulation::vertex_star;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  try {
    deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    FAIL() << "expected an error";
  } catch (const SettingError& e) {
    EXPECT_NE(std::string(e.what()).find("deformation.volume"), std::string::npos) << e.what();
  }
}
