#include "voxelize/voxelize_plan.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

TEST(VoxelizePlan, OrgansOutsideTheFieldOfViewAreSkipped) {
  Scene scene;
  scene.grid.field_of_view_mm = {100, 100, 100};
  OrganSettings inside{"inside", "csf", "", "", true, 0, {}};
  inside.shape.radii_mm = {10, 10, 10};
  OrganSettings outside = inside;
  outside.name = "outside";
  outside.shape.center_mm = {0, 0, 70}; // spans z in [60, 80], the field of view ends at 50
  OrganSettings touching = inside;
  touching.name = "touching";
  touching.shape.center_mm = {0, 0, 55}; // spans z in [45, 65]
  scene.anatomy.organs = {inside, outside, touching};
  EXPECT_TRUE(organ_in_field_of_view(scene, inside));
  EXPECT_FALSE(organ_in_field_of_view(scene, outside));
  EXPECT_TRUE(organ_in_field_of_view(scene, touching));
  const StageReport report = plan_voxelize(scene);
  EXPECT_NE(std::find(report.skipped.begin(), report.skipped.end(), "outside: outside the field of view"),
            report.skipped.end());
}

TEST(VoxelizePlan, FieldsAndJacobianAreSkippedWhenNothingDeforms) {
  Scene scene;
  const StageReport report = plan_voxelize(scene);
  EXPECT_NE(std::find(report.skipped.begin(), report.skipped.end(),
                      "displacement fields both ways (nothing deforms)"),
            report.skipped.end());
}
