#include "anatomy/anatomy_plan.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

TEST(AnalyticShapeBounds, EllipsoidBoundsFollowItsRotation) {
  ShapeSettings shape;
  shape.center_mm = {1, 2, 3};
  shape.radii_mm = {10, 20, 30};
  auto box = analytic_shape_bounds(shape);
  ASSERT_TRUE(box);
  EXPECT_TRUE(box->max_mm.isApprox(Eigen::Vector3d(11, 22, 33)));
  shape.rotation_deg = {0, 0, 90}; // x and y radii swap
  box = analytic_shape_bounds(shape);
  EXPECT_TRUE((box->max_mm - shape.center_mm).isApprox(Eigen::Vector3d(20, 10, 30), 1e-12));
  // At 45 degrees about z the x extent is sqrt((10^2 + 20^2) / 2), tighter than the box bound.
  shape.rotation_deg = {0, 0, 45};
  box = analytic_shape_bounds(shape);
  EXPECT_NEAR(box->max_mm.x() - 1.0, std::sqrt(250.0), 1e-12);
}

TEST(AnalyticShapeBounds, FileShapesHaveNoBoundsUntilRead) {
  ShapeSettings shape;
  shape.kind = ShapeKind::mesh;
  EXPECT_FALSE(analytic_shape_bounds(shape));
}

TEST(OrganTable, ResolvesParentsAndCountsContainingOrgans) {
  AnatomySettings anatomy;
  anatomy.organs = {{"scalp", "skin", "", "", true, 0, {}, 1.0, {}},
                    {"skull", "bone_cortical", "", "scalp", true, 0, {}, 1.0, {}},
                    {"brain", "white_matter", "", "skull", true, 0, {}, 1.0, {}}};
  const OrganTable organs = organ_table(anatomy);
  EXPECT_EQ(organs[0].depth, 0);
  EXPECT_EQ(organs[0].parent, -1);
  EXPECT_EQ(organs[2].depth, 2);
  EXPECT_EQ(organs[2].parent, 1);
  EXPECT_EQ(organs.index_of("skull"), 1);
  EXPECT_EQ(organs.index_of("liver"), -1);
  const StageReport report = plan_anatomy(anatomy, organs);
  ASSERT_EQ(report.modelled.size(), 3u);
  EXPECT_NE(report.modelled[2].find("inside skull (depth 2)"), std::string::npos) << report.modelled[2];
}

TEST(AnatomyPlan, StatesEachOrgansOwnBaseSizeAndItsTetSize) {
  AnatomySettings anatomy; // the scene's base size: 320
  OrganSettings ball, pea;
  ball.name = "ball", pea.name = "pea";
  ball.tissue = pea.tissue = "muscle_skeletal";
  ball.base_mesh_triangles = 100000; // its own
  pea.solid = false;
  anatomy.organs = {ball, pea};
  anatomy.organs[0].shape.radii_mm = {50, 45, 40};
  const StageReport report = plan_anatomy(anatomy, organ_table(anatomy));
  ASSERT_EQ(report.modelled.size(), 2u);
  // What the run builds: the organ's own 100000, not the scene's 320.
  EXPECT_NE(report.modelled[0].find("surface of 100000 base triangles (its own base_mesh_triangles)"),
            std::string::npos)
      << report.modelled[0];
  // Area 25400 mm^2 over 100000 triangles: edges of 1.35 x 0.77 = 1.03 mm.
  EXPECT_NE(report.modelled[0].find("tets of about 1."), std::string::npos) << report.modelled[0];
  EXPECT_NE(report.modelled[1].find("surface of 320 base triangles with"), std::string::npos)
      << report.modelled[1];
}
