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
  EXPECT_EQ(plan_mri(MriSettings{}, OrganTable{}, GridSettings{}).status, "skipped");
}

// A k-space acquisition on a grid with a slow transform size names the next fast sizes in the
// run's log; on fast sizes, or without k-space, nothing is said.
TEST(MriPlan, AKspaceGridOfSlowTransformSizesIsNamedWithFasterOnes) {
  MriSettings mri;
  mri.sequences.push_back(SequenceSettings{"T1w", SequenceKind::spin_echo, 500.0, 10.0});
  mri.acquisition.kspace = true;
  const auto kspace_line = [&](const GridSettings& grid) {
    for (const std::string& line : plan_mri(mri, OrganTable{}, grid).modelled)
      if (line.rfind("k-space truncation", 0) == 0) return line;
    return std::string();
  };
  GridSettings grid;
  grid.field_of_view_mm = {203, 237, 197};
  const std::string slow = kspace_line(grid);
  EXPECT_NE(slow.find("the grid's 203 x 237 x 197 voxels have prime factors above 13"), std::string::npos)
      << slow;
  EXPECT_NE(slow.find("208 x 240 x 198 would not"), std::string::npos) << slow;
  grid.field_of_view_mm = {189, 217, 192}; // 217 = 7 x 31
  EXPECT_NE(kspace_line(grid).find("189 x 220 x 192 would not"), std::string::npos) << kspace_line(grid);
  grid.field_of_view_mm = {208, 240, 200}; // 13 along x: fast
  const std::string fast = kspace_line(grid);
  EXPECT_FALSE(fast.empty());
  EXPECT_EQ(fast.find("prime"), std::string::npos) << fast;
  mri.acquisition.kspace = false;
  grid.field_of_view_mm = {203, 237, 197};
  for (const std::string& line : plan_mri(mri, OrganTable{}, grid).modelled)
    EXPECT_EQ(line.find("prime"), std::string::npos) << line;
}
