#include "voxelize/voxelize_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace phantasm;

TEST(VoxelizePlan, OrgansOutsideTheFieldOfViewAreSkipped) {
  GridSettings grid;
  grid.field_of_view_mm = {100, 100, 100};
  ShapeSettings inside;
  inside.radii_mm = {10, 10, 10};
  ShapeSettings outside = inside;
  outside.center_mm = {0, 0, 70}; // spans z in [60, 80], the field of view ends at 50
  ShapeSettings touching = inside;
  touching.center_mm = {0, 0, 55}; // spans z in [45, 65]
  EXPECT_TRUE(organ_in_field_of_view(analytic_shape_bounds(inside), grid.grid()));
  EXPECT_FALSE(organ_in_field_of_view(analytic_shape_bounds(outside), grid.grid()));
  EXPECT_TRUE(organ_in_field_of_view(analytic_shape_bounds(touching), grid.grid()));
  VoxelizationSettings settings;
  settings.organ_bounds_mm = {analytic_shape_bounds(inside), analytic_shape_bounds(outside),
                              analytic_shape_bounds(touching)};
  const OrganTable organs({{"inside", "csf", ""}, {"outside", "csf", ""}, {"touching", "csf", ""}});
  const StageReport report = plan_voxelize(settings, organs, grid);
  EXPECT_NE(std::find(report.skipped.begin(), report.skipped.end(), "outside: outside the field of view"),
            report.skipped.end());
  EXPECT_EQ(std::count(report.modelled.begin(), report.modelled.end(),
                       "touching: level set, reference and deformed"),
            1);
  // A warning too (recorded in provenance.json, an error with --strict): nothing shows the organ.
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_EQ(report.warnings[0].rfind("outside: outside the field of view", 0), 0u) << report.warnings[0];
}

TEST(VoxelizePlan, AnOrganSmallerThanAVoxelWarns) {
  GridSettings grid;
  grid.field_of_view_mm = {100, 100, 100};
  grid.voxel_size_mm = Eigen::Vector3d::Constant(4.0);
  ShapeSettings grain;
  grain.radii_mm = {1.5, 1.5, 1.5}; // 3 mm across
  ShapeSettings pea = grain;
  pea.radii_mm = {2.5, 2.5, 2.5}; // 5 mm across
  VoxelizationSettings settings;
  settings.organ_bounds_mm = {analytic_shape_bounds(grain), analytic_shape_bounds(pea)};
  const OrganTable organs({{"grain", "csf", ""}, {"pea", "csf", ""}});
  const StageReport report = plan_voxelize(settings, organs, grid);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("grain: spans at most 3 mm, less than a voxel (4 mm)"), std::string::npos)
      << report.warnings[0];
}

TEST(VoxelizePlan, FieldsAndJacobianAreSkippedWhenNothingDeforms) {
  const StageReport report = plan_voxelize(VoxelizationSettings{}, OrganTable{}, GridSettings{});
  EXPECT_NE(std::find(report.skipped.begin(), report.skipped.end(),
                      "displacement fields both ways (nothing deforms)"),
            report.skipped.end());
}
