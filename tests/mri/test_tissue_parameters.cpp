#include "mri/mri_plan.hpp"
#include "mri/tissue_parameters.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

TEST(TissueParameters, SceneValuesWinAndTheTableFillsTheRest) {
  MriSettings mri;
  mri.field_strength_T = 3.0;
  const OrganTable organs({{"a", "csf", ""}, {"b", "white_matter", ""}, {"c", "csf", "a"}});
  TissueOverride csf;
  csf.tissue = "csf";
  csf.T2star_ms = 100.0;
  csf.T1_ms = 4000.0;
  mri.tissues = {csf};
  const auto resolved = resolve_tissue_parameters(mri, organs);
  ASSERT_EQ(resolved.size(), 2u);
  const TissueParameters& p = resolved.at("csf");
  EXPECT_DOUBLE_EQ(*p.T1_ms, 4000.0);
  EXPECT_EQ(p.T1_source, "scene");
  EXPECT_DOUBLE_EQ(*p.T2_ms, 2000.0);
  EXPECT_NE(p.T2_source.find("SpinSight"), std::string::npos);
  EXPECT_DOUBLE_EQ(*p.T2star_ms, 100.0);
  EXPECT_DOUBLE_EQ(*resolved.at("white_matter").T1_ms, 810.0);
}

TEST(MriPlan, NoSequencesMeansNoImages) {
  EXPECT_EQ(plan_mri(MriSettings{}, OrganTable{}).status, "skipped");
}
