#include "sim/sim_plan.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

namespace {
Scene three_organs() {
  Scene scene;
  scene.anatomy.organs = {{"skull", "bone_cortical", "", "", true, 0, {}},
                          {"brain", "white_matter", "", "skull", true, 0, {}},
                          {"eye", "csf", "", "", true, 0, {}}};
  return scene;
}
} // namespace

TEST(OrganMotion, NothingIsSimulatedWithoutDeformation) {
  const Scene scene = three_organs();
  EXPECT_EQ(classify_organ_motion(scene), std::vector<OrganMotion>(3, OrganMotion::rigid));
  EXPECT_EQ(plan_sim(scene).status, "skipped");
}

TEST(OrganMotion, LoadedOrgansAreSimulatedFixedOnesHeldAndTheRestCarriedRigidly) {
  Scene scene = three_organs();
  scene.deformation.mode = DeformationMode::quasi_static;
  scene.deformation.fixed = {"skull"};
  LoadSettings push;
  push.kind = LoadKind::displacement;
  push.organ = "brain";
  scene.deformation.loads = {push};
  EXPECT_EQ(classify_organ_motion(scene),
            (std::vector<OrganMotion>{OrganMotion::fixed, OrganMotion::simulated, OrganMotion::rigid}));
  const StageReport report = plan_sim(scene);
  ASSERT_EQ(report.skipped.size(), 1u);
  EXPECT_NE(report.skipped[0].find("eye"), std::string::npos);
}

TEST(OrganMotion, GravityWithoutAnOrganListActsOnEveryOrganThatIsNotFixed) {
  Scene scene = three_organs();
  scene.deformation.mode = DeformationMode::dynamic;
  scene.deformation.fixed = {"skull"};
  scene.deformation.loads = {LoadSettings{}};
  EXPECT_EQ(classify_organ_motion(scene),
            (std::vector<OrganMotion>{OrganMotion::fixed, OrganMotion::simulated, OrganMotion::simulated}));
}

TEST(OrganMotion, ThePlanNamesEmbeddedOrgansObstaclesAndLoadSteps) {
  Scene scene = three_organs();
  scene.deformation.mode = DeformationMode::quasi_static;
  scene.deformation.load_steps = 3;
  LoadSettings push;
  push.kind = LoadKind::displacement;
  push.organ = "skull";
  scene.deformation.loads = {push};
  ObstacleSettings paddle;
  paddle.point_mm = {0, 0, 40};
  paddle.normal = {0, 0, -1};
  scene.deformation.obstacles = {paddle};
  const StageReport report = plan_sim(scene);
  auto modelled = [&](const std::string& text) {
    for (const std::string& line : report.modelled)
      if (line.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(modelled("brain: no load of its own; inside the simulated skull, it follows it"))
      << report.modelled.size();
  EXPECT_TRUE(modelled("half-space obstacle through (0, 0, 40) mm, normal (0, 0, -1)"));
  EXPECT_TRUE(modelled("loads applied in 3 steps"));
  ASSERT_EQ(report.skipped.size(), 1u); // the eye, outside
  EXPECT_NE(report.skipped[0].find("eye"), std::string::npos);
}
