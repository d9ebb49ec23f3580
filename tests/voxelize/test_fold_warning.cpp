// The warning for a field that folds inside its exact mask (#44 item 4): both fields alike, the
// count and the organs named, the background not called tissue.
#include "voxelize/fold_warning.hpp"

#include <gtest/gtest.h>

#include <cmath>

using phantasm::fold_warning;

namespace {

const std::vector<std::string> k_names = {"brain", "skull"};

} // namespace

TEST(FoldWarning, NoneWhenEveryExactVoxelHasAPositiveDeterminant) {
  // A fold outside the mask (the smooth extension) is not the ground truth's: no warning.
  const std::vector<float> jacobian = {1.0f, 0.5f, -1.0f, 2.0f};
  const std::vector<std::uint8_t> exact = {1, 1, 0, 1};
  const std::vector<std::int32_t> labels = {1, 1, 1, 2};
  EXPECT_FALSE(fold_warning("from-ref_to-def (the deformed grid)", jacobian, exact, labels, k_names));
}

TEST(FoldWarning, NamesTheCountTheSmallestAndTheOrgansByTheFieldsOwnLabels) {
  const std::vector<float> jacobian = {-0.5f, 0.0f, -2.03f, 1.0f, -7.0f};
  const std::vector<std::uint8_t> exact = {1, 1, 1, 1, 0};
  const std::vector<std::int32_t> labels = {1, 2, 2, 1, 1};
  const auto warning = fold_warning("from-ref_to-def (the deformed grid)", jacobian, exact, labels, k_names);
  ASSERT_TRUE(warning);
  EXPECT_EQ(*warning, "3 voxels of the exact mask of from-ref_to-def (the deformed grid) have a Jacobian "
                      "determinant <= 0 (smallest -2.03): 3 in brain (1), skull (2): the deformation folds "
                      "tissue there (see the sim stage's loads)");
}

TEST(FoldWarning, BackgroundVoxelsAreCountedApartAndNotCalledTissue) {
  const std::vector<float> jacobian = {-1.0f, -0.25f, 1.0f};
  const std::vector<std::uint8_t> exact = {1, 1, 1};
  const std::vector<std::int32_t> background_only = {0, 0, 1};
  const auto only =
      fold_warning("from-def_to-ref (the reference grid)", jacobian, exact, background_only, k_names);
  ASSERT_TRUE(only);
  EXPECT_EQ(only->find("folds tissue"), std::string::npos) << *only;
  EXPECT_NE(only->find("2 voxels of the exact mask of from-def_to-ref"), std::string::npos) << *only;
  EXPECT_NE(only->find("2 in the background (label 0, no organ's tissue)"), std::string::npos) << *only;

  const std::vector<std::int32_t> mixed = {0, 2, 1};
  const auto both = fold_warning("from-def_to-ref (the reference grid)", jacobian, exact, mixed, k_names);
  ASSERT_TRUE(both);
  EXPECT_NE(both->find("1 in skull (1): the deformation folds tissue there"), std::string::npos) << *both;
  EXPECT_NE(both->find("; 1 in the background"), std::string::npos) << *both;
}

TEST(FoldWarning, ANaNDeterminantIsAFoldAndALabelBeyondTheNamesIsNumbered) {
  const std::vector<float> jacobian = {std::nanf(""), 1.0f};
  const std::vector<std::uint8_t> exact = {1, 1};
  const std::vector<std::int32_t> labels = {3, 1};
  const auto warning = fold_warning("from-ref_to-def (the deformed grid)", jacobian, exact, labels, k_names);
  ASSERT_TRUE(warning);
  EXPECT_NE(warning->find("(smallest NaN): 1 in label 3 (1)"), std::string::npos) << *warning;
}
