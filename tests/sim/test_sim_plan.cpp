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
