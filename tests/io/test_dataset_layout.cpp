#include "core/error.hpp"
#include "io/dataset_layout.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

using namespace phantasm;
namespace fs = std::filesystem;

TEST(DatasetLayout, PathsFollowTheLayoutOfTheDesign) {
  const DatasetLayout layout("out", "01");
  EXPECT_EQ(layout.dataset_description(), fs::path("out/dataset_description.json"));
  EXPECT_EQ(layout.anat_image(PhantomState::reference, "T1w"),
            fs::path("out/sub-01/ses-ref/anat/sub-01_ses-ref_T1w.nii.gz"));
  EXPECT_EQ(layout.anat_image(PhantomState::deformed, "T1w"),
            fs::path("out/sub-01/ses-def/anat/sub-01_ses-def_T1w.nii.gz"));
  EXPECT_EQ(layout.dseg_table(), fs::path("out/derivatives/phantasm/dseg.tsv"));
  EXPECT_EQ(layout.dseg(PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz"));
  EXPECT_EQ(layout.readme(), fs::path("out/README"));
  EXPECT_EQ(layout.probseg(PhantomState::reference, "csf"),
            fs::path("out/derivatives/phantasm/sub-01/ses-ref/anat/sub-01_ses-ref_label-csf_probseg.nii.gz"));
  EXPECT_EQ(
      layout.probseg(PhantomState::deformed, "gray_matter"),
      fs::path(
          "out/derivatives/phantasm/sub-01/ses-def/anat/sub-01_ses-def_label-grayMatter_probseg.nii.gz"));
  // BIDS names: from-A_to-B brings an image in A's space into B's space.
  EXPECT_EQ(layout.transform(PhantomState::reference, PhantomState::deformed),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-ref_to-def_mode-image_xfm.nii.gz"));
  EXPECT_EQ(layout.transform(PhantomState::deformed, PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-def_to-ref_mode-image_xfm.nii.gz"));
  EXPECT_EQ(layout.transform_mask(PhantomState::deformed, PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-def_to-ref_desc-exact_mask.nii.gz"));
  EXPECT_EQ(layout.jacobian(PhantomState::deformed, PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-def_to-ref_jacobian.nii.gz"));
  EXPECT_EQ(layout.jacobian(PhantomState::reference, PhantomState::deformed),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-ref_to-def_jacobian.nii.gz"));
  // Files named ses-<state> lie in ses-<state> folders, as BIDS requires.
  EXPECT_EQ(layout.landmarks(PhantomState::deformed),
            fs::path("out/derivatives/phantasm/sub-01/ses-def/landmarks/sub-01_ses-def_landmarks.csv"));
  EXPECT_EQ(
      layout.mesh(PhantomState::reference, "ventricle_left"),
      fs::path("out/derivatives/phantasm/sub-01/ses-ref/meshes/sub-01_ses-ref_organ-ventricleLeft_mesh.vtp"));
  EXPECT_EQ(
      layout.tet_mesh(PhantomState::deformed, "white_matter"),
      fs::path(
          "out/derivatives/phantasm/sub-01/ses-def/meshes/sub-01_ses-def_organ-whiteMatter_tetmesh.vtu"));
  EXPECT_EQ(layout.vdb(PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/ses-ref/vdb/sub-01_ses-ref_grids.vdb"));
  EXPECT_EQ(layout.preview(PhantomState::deformed, "T1w"),
            fs::path("out/derivatives/phantasm/sub-01/ses-def/previews/sub-01_ses-def_T1w.png"));
  EXPECT_EQ(layout.provenance(), fs::path("out/derivatives/phantasm/sub-01/provenance.json"));
}

// BIDS parsers split file names at '_' and '-': entity values are the names in camelCase.
TEST(DatasetLayout, EntityValuesHoldLettersAndDigitsOnly) {
  EXPECT_EQ(bids_entity_value("csf"), "csf");
  EXPECT_EQ(bids_entity_value("gray_matter"), "grayMatter");
  EXPECT_EQ(bids_entity_value("ventricle-left"), "ventricleLeft");
  EXPECT_EQ(bids_entity_value("_lesion__2_b."), "lesion2B");
  EXPECT_EQ(bids_entity_value("T1 map"), "T1Map");
}

TEST(DatasetLayout, SidecarsReplaceTheWholeImageExtension) {
  EXPECT_EQ(sidecar_path("a/sub-01_ses-ref_T1w.nii.gz"), fs::path("a/sub-01_ses-ref_T1w.json"));
  EXPECT_EQ(sidecar_path("a/x_xfm.nii"), fs::path("a/x_xfm.json"));
}

TEST(OutputFolder, IsCreatedWhenMissingAndRefusedWhenItHoldsFilesUnlessForced) {
  const fs::path folder = phantasm::testing::fresh_folder("output");
  fs::remove_all(folder); // missing: created
  prepare_output_folder(folder, false);
  EXPECT_TRUE(fs::is_directory(folder));
  prepare_output_folder(folder, false); // empty: fine
  std::ofstream(folder / "keep.txt") << "user data";
  // A process that has ended left a temporary file (its pid names it).
  const pid_t ended = ::fork();
  if (ended == 0) ::_exit(0);
  ::waitpid(ended, nullptr, 0);
  const std::string stale = ".keep.txt.phantasm-tmp-" + std::to_string(ended) + "-0";
  std::ofstream(folder / stale) << "left by a killed run";
  try {
    prepare_output_folder(folder, false);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos);
  }
  prepare_output_folder(folder, true);
  EXPECT_TRUE(fs::exists(folder / "keep.txt"));
  EXPECT_FALSE(fs::exists(folder / stale));
  EXPECT_THROW(prepare_output_folder(folder / "keep.txt", true), InputError);
}
