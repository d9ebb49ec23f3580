#include "sim/sim_plan.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

namespace {
const OrganTable
    k_organs({{"skull", "bone_cortical", ""}, {"brain", "white_matter", "skull"}, {"eye", "csf", ""}});
} // namespace

TEST(OrganMotion, NothingIsSimulatedWithoutDeformation) {
  const DeformationSettings deformation;
  EXPECT_EQ(classify_organ_motion(deformation, k_organs), std::vector<OrganMotion>(3, OrganMotion::rigid));
  EXPECT_EQ(plan_sim(deformation, k_organs).status, "skipped");
}

TEST(OrganMotion, LoadedOrgansAreSimulatedFixedOnesHeldAndTheRestCarriedRigidly) {
  DeformationSettings deformation;
  deformation.mode = DeformationMode::quasi_static;
  deformation.fixed = {"skull"};
  LoadSettings push;
  push.kind = LoadKind::displacement;
  push.organ = "brain";
  deformation.loads = {push};
  EXPECT_EQ(classify_organ_motion(deformation, k_organs),
            (std::vector<OrganMotion>{OrganMotion::fixed, OrganMotion::simulated, OrganMotion::rigid}));
  const StageReport report = plan_sim(deformation, k_organs);
  ASSERT_EQ(report.skipped.size(), 1u);
  EXPECT_NE(report.skipped[0].find("eye"), std::string::npos);
}

TEST(OrganMotion, GravityWithoutAnOrganListActsOnEveryOrganThatIsNotFixed) {
  DeformationSettings deformation;
  deformation.mode = DeformationMode::dynamic;
  deformation.fixed = {"skull"};
  deformation.loads = {LoadSettings{}};
  EXPECT_EQ(classify_organ_motion(deformation, k_organs),
            (std::vector<OrganMotion>{OrganMotion::fixed, OrganMotion::simulated, OrganMotion::simulated}));
}

TEST(OrganMotion, ThePlanNamesEmbeddedOrgansObstaclesAndLoadSteps) {
  DeformationSettings deformation;
  deformation.mode = DeformationMode::quasi_static;
  deformation.load_steps = 3;
  LoadSettings push;
  push.kind = LoadKind::displacement;
  push.organ = "skull";
  deformation.loads = {push};
  ObstacleSettings paddle;
  paddle.point_mm = {0, 0, 40};
  paddle.normal = {0, 0, -1};
  deformation.obstacles = {paddle};
  const StageReport report = plan_sim(deformation, k_organs);
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
