// The phantasm command on a head from a whole segmentation (anatomy.segmentation): a small aseg
// with its FreeSurfer lookup table becomes a dataset whose labels are the aseg's, grouped by the
// freesurfer mapping's organs; a volume label missing from the table is bad input.

#include "io/nifti_file.hpp"
#include "tests/support/aseg_fixture.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const std::string k_scene = R"(phantasm: 1
name: aseg
seed: 1
field_strength_T: 3.0
grid: {field_of_view_mm: 96, voxel_size_mm: 2}
anatomy:
  base_mesh_triangles: 80
  segmentation: {file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer}
sequences:
  - {name: T1w, type: spin_echo, TR_ms: 500, TE_ms: 10}
)";

} // namespace

TEST(SegmentationRun, AnAsegBecomesADatasetWhoseOrgansMatchItsLabels) {
  const fs::path folder = write_aseg_fixture("segmentation-run");
  write_text_file(folder / "scene.yaml", k_scene);
  const fs::path out = folder / "out";
  const CommandResult run = run_command(
      {PHANTASM_EXECUTABLE, "run", (folder / "scene.yaml").string(), "-o", out.string(), "--quiet"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ImageGrid aseg_grid, dseg_grid;
  const std::vector<std::int32_t> aseg = read_nifti_labels(folder / "aseg.nii.gz", &aseg_grid);
  const std::vector<std::int32_t> dseg = read_nifti_labels(
      out / "derivatives" / "phantasm" / "sub-01" / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz",
      &dseg_grid);
  ASSERT_EQ(aseg.size(), dseg.size());
  EXPECT_TRUE(dseg_grid.world_from_voxel.isApprox(aseg_grid.world_from_voxel));
  const std::map<std::string, int> value = dseg_table(out / "derivatives" / "phantasm" / "dseg.tsv");
  // Each organ's voxels against the aseg labels the mapping gives it (Dice 0.92 to 1.0 measured).
  const std::map<std::string, std::vector<std::int32_t>> organs = {{"csf", {24}},
                                                                   {"grey_matter", {3, 42}},
                                                                   {"white_matter", {2, 41}},
                                                                   {"brainstem", {16}},
                                                                   {"left_lateral_ventricle", {4}},
                                                                   {"right_lateral_ventricle", {43}},
                                                                   {"left_thalamus", {10}},
                                                                   {"right_thalamus", {49}},
                                                                   {"left_hippocampus", {17}},
                                                                   {"right_hippocampus", {53}}};
  ASSERT_EQ(value.size(), organs.size() + 1) << "the background and one label per organ";
  for (const auto& [organ, labels] : organs) {
    ASSERT_EQ(value.count(organ), 1u) << organ;
    std::size_t in_aseg = 0, in_dseg = 0, both = 0;
    for (std::size_t i = 0; i < aseg.size(); ++i) {
      const bool a = std::find(labels.begin(), labels.end(), aseg[i]) != labels.end();
      const bool d = dseg[i] == value.at(organ);
      in_aseg += a;
      in_dseg += d;
      both += a && d;
    }
    EXPECT_GT(2.0 * static_cast<double>(both) / static_cast<double>(in_aseg + in_dseg), 0.9) << organ;
  }
}

TEST(SegmentationRun, AVolumeLabelMissingFromItsTableExitsWithTwoAndWritesNothing) {
  const fs::path folder = write_aseg_fixture("segmentation-run-missing", 77);
  write_text_file(folder / "scene.yaml", k_scene);
  const fs::path out = folder / "out";
  const CommandResult run =
      run_command({PHANTASM_EXECUTABLE, "run", (folder / "scene.yaml").string(), "-o", out.string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("scene.yaml:8:"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("label 77 has voxels but no line in"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
}
