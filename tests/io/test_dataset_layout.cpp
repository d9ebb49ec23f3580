#include "core/error.hpp"
#include "io/dataset_layout.hpp"

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
  EXPECT_EQ(layout.probseg(PhantomState::reference, "csf"),
            fs::path("out/derivatives/phantasm/sub-01/ses-ref/anat/sub-01_ses-ref_label-csf_probseg.nii.gz"));
  EXPECT_EQ(layout.transform(PhantomState::reference, PhantomState::deformed),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-ref_to-def_mode-image_xfm.nii.gz"));
  EXPECT_EQ(layout.transform(PhantomState::deformed, PhantomState::reference),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-def_to-ref_mode-image_xfm.nii.gz"));
  EXPECT_EQ(layout.jacobian(),
            fs::path("out/derivatives/phantasm/sub-01/xfm/sub-01_from-ref_to-def_jacobian.nii.gz"));
  EXPECT_EQ(layout.landmarks(PhantomState::deformed),
            fs::path("out/derivatives/phantasm/sub-01/landmarks/sub-01_ses-def_landmarks.csv"));
  EXPECT_EQ(layout.provenance(), fs::path("out/derivatives/phantasm/sub-01/provenance.json"));
}

TEST(DatasetLayout, SidecarsReplaceTheWholeImageExtension) {
  EXPECT_EQ(sidecar_path("a/sub-01_ses-ref_T1w.nii.gz"), fs::path("a/sub-01_ses-ref_T1w.json"));
  EXPECT_EQ(sidecar_path("a/x_xfm.nii"), fs::path("a/x_xfm.json"));
}

TEST(OutputFolder, IsCreatedWhenMissingAndRefusedWhenItHoldsFilesUnlessForced) {
  const fs::path folder = fs::temp_directory_path() / ("phantasm-test-output-" + std::to_string(::getpid()));
  fs::remove_all(folder);
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
