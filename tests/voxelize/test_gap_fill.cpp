// The gaps of the deformed state (docs/volumes-and-images.md, "The gap"): which organs leave
// one, where it sits in the nesting, and what fills it.

#include "core/error.hpp"
#include "voxelize/gap_fill.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

namespace {

// A bone box holding a soft ball (with a core embedded in it) and a pocket of CSF.
const OrganTable k_organs({{"box", "bone_cortical", ""},
                           {"ball", "gray_matter", "box"},
                           {"core", "white_matter", "ball"},
                           {"pocket", "csf", "box"}});
const std::vector<std::string> k_tissues{"bone_cortical", "gray_matter", "white_matter", "csf"};

PhantomDeformation moved_ball() {
  PhantomDeformation d;
  for (const auto& [organ, by] : std::vector<std::pair<std::string, std::string>>{
           {"box", "fixed"}, {"ball", "solver"}, {"core", "embedded in ball"}, {"pocket", "rigid"}}) {
    OrganDeformation o;
    o.organ = organ;
    o.moved_by = by;
    d.organs.push_back(o);
  }
  return d;
}

/// The reference organs as the voxelizer sees them (no level sets needed: a gap takes the
/// pointer of its organ's).
std::vector<VoxelizedOrgan> reference_organs() {
  std::vector<VoxelizedOrgan> organs;
  for (std::size_t o = 0; o < k_organs.size(); ++o) {
    VoxelizedOrgan v;
    v.level_set = reinterpret_cast<const LevelSet*>(0x1000 + 0x100 * o);
    v.depth = 2 * k_organs[o].depth;
    v.label = static_cast<int>(o) + 1;
    v.tissue = static_cast<int>(o);
    organs.push_back(v);
  }
  return organs;
}

} // namespace

TEST(GapFill, TheGapTissueIsAirOrATissueOfTheOrgansElseASettingError) {
  EXPECT_EQ(gap_tissue_index("air", k_tissues), -1);
  EXPECT_EQ(gap_tissue_index("csf", k_tissues), 3);
  try {
    gap_tissue_index("vacuum", k_tissues);
    FAIL() << "expected a SettingError";
  } catch (const SettingError& error) {
    EXPECT_EQ(error.key_path(), "deformation.gap_tissue");
    EXPECT_NE(error.message().find("found 'vacuum'"), std::string::npos) << error.message();
  }
}

TEST(GapFill, AMovedOrganLeavesAGapInAContainerThatStaysNotInOneThatMoves) {
  StageReport report;
  const std::vector<VoxelizedOrgan> reference = reference_organs();
  const std::vector<VoxelizedOrgan> gaps = gap_organs("csf", 3, k_organs, moved_ball(), reference, report);
  // The ball leaves a gap in the box; the core moves with its container, the pocket stays.
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0].level_set, reference[1].level_set); // the ball's reference shape
  EXPECT_EQ(gaps[0].label, 5);                          // after the four organs
  EXPECT_EQ(gaps[0].tissue, 3);
  // Between the box (depth 0) and the organs it holds (depth 2): a deformed organ in the box
  // covers the gap, the box does not.
  EXPECT_EQ(gaps[0].depth, 1);
  ASSERT_EQ(report.modelled.size(), 1u);
  EXPECT_NE(report.modelled[0].find("ball in box"), std::string::npos) << report.modelled[0];
}

TEST(GapFill, NothingMovedNoGapAndAContainerOutsideTheGridNoGap) {
  StageReport report;
  PhantomDeformation still = moved_ball();
  for (OrganDeformation& o : still.organs)
    o.moved_by = "rigid";
  EXPECT_TRUE(gap_organs("air", -1, k_organs, still, reference_organs(), report).empty());
  std::vector<VoxelizedOrgan> without_box = reference_organs();
  without_box.erase(without_box.begin());
  EXPECT_TRUE(gap_organs("air", -1, k_organs, moved_ball(), without_box, report).empty());
  EXPECT_TRUE(report.modelled.empty());
}
