// The ground-truth fields of `phantasm run`, checked by real clients: Debian's transformix applies
// each field as BIDS names it, from-A_to-B to state A's label map (nearest neighbour:
// FinalBSplineInterpolator of order 0), and must get state B's labels; numpy/scipy composes the
// two fields (tests/apps/check_fields.py).

#include "io/dataset_layout.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/apps/transformix_parameters.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

fs::path run_transformix(const fs::path& moving, const fs::path& field, const phantasm::ImageGrid& grid,
                         const fs::path& folder) {
  fs::create_directories(folder);
  write_text_file(folder / "parameters.txt", deformation_field_parameters(field, grid));
  const CommandResult result = run_command({"/usr/bin/transformix", "-in", moving.string(), "-out",
                                            folder.string(), "-tp", (folder / "parameters.txt").string()});
  EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
  return folder / "result.nii.gz";
}

} // namespace

TEST(GroundTruthFields, TransformixWithTheFieldFromAToBTurnsAsLabelsIntoBsAndTheFieldsInvertEachOther) {
  const fs::path root = fresh_folder("fields");
  const fs::path out = root / "out";
  const CommandResult run =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "-q"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const fs::path sub = out / "derivatives" / "phantasm" / "sub-01";
  phantasm::ImageGrid grid;
  const auto reference =
      phantasm::read_nifti_labels(sub / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz", &grid);
  const auto deformed =
      phantasm::read_nifti_labels(sub / "ses-def" / "anat" / "sub-01_ses-def_dseg.nii.gz", nullptr);
  ASSERT_NE(reference, deformed); // the scene deforms: the test would prove nothing otherwise

  const phantasm::DatasetLayout layout(out, "01");
  const auto ref = phantasm::PhantomState::reference, def = phantasm::PhantomState::deformed;
  const fs::path to_reference =
      run_transformix(layout.dseg(def), layout.transform(def, ref), grid, root / "to-ref");
  const fs::path to_deformed =
      run_transformix(layout.dseg(ref), layout.transform(ref, def), grid, root / "to-def");
  const CommandResult check =
      run_command({PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_fields.py").string(),
                   out.string(), to_reference.string(), to_deformed.string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  std::printf("%s", check.out.c_str());
}

namespace {

/// A shipped scene, its organs that stay where they are, and the text swapped to run it cheaply.
struct StillScene {
  const char* file;
  std::vector<std::string> still;
  std::vector<std::pair<std::string, std::string>> swaps;
};

/// The shipped scene with every swap made and its outputs cut to labels, fields and Jacobians
/// (no images, previews, meshes or landmarks), written to folder/scene.yaml.
fs::path cheap_variant(const StillScene& s, const fs::path& folder) {
  std::string text = read_file(k_source_dir / "data-synthetic" / s.file);
  auto swap = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << s.file << " lacks " << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  };
  for (const auto& [from, to] : s.swaps)
    swap(from, to);
  if (text.find("\noutputs:\n") == std::string::npos) text += "\noutputs:\n";
  swap("\noutputs:\n", "\noutputs:\n  images: false\n  previews: false\n  meshes: false\n  landmarks: false\n"
                       "  parameter_maps: false\n");
  fs::create_directories(folder);
  write_text_file(folder / "scene.yaml", text);
  return folder / "scene.yaml";
}

} // namespace

// Tissue that does not move is still in both fields, inside and outside the exact masks, and the
// from-def_to-ref Jacobian tells every organ's volume change as the labels do (within 1 % of
// its volume, organs of 20 ml or more): the shipped head (at 2 mm) and abdomen, whose fixed and
// rigid organs border a moved one (tests/apps/check_still_tissue.py).
TEST(GroundTruthFields, StillOrgansStayExactlyStillAndTheJacobianTellsEachOrgansVolumeChange) {
  const std::vector<StillScene> scenes = {
      {"head.yaml",
       {"scalp", "skull"},
       {{"voxel_size_mm: 1.0", "voxel_size_mm: 2.0"}, {"acquired_voxel_mm: 1.2", "acquired_voxel_mm: 2.4"}}},
      {"abdomen.yaml",
       {"subcutaneous_fat", "body_wall", "abdominal_cavity", "spleen", "kidney_right", "medulla_right",
        "kidney_left", "medulla_left", "vertebra"},
       {}},
  };
  for (const StillScene& s : scenes) {
    const fs::path root = fresh_folder(std::string("still-") + s.file);
    const fs::path scene = cheap_variant(s, root);
    const CommandResult run =
        run_command({k_phantasm, "run", scene.string(), "-o", (root / "out").string(), "-q"});
    ASSERT_EQ(run.exit_code, 0) << s.file << ": " << run.err;
    std::vector<std::string> check = {PHANTASM_PYTHON,
                                      (k_source_dir / "tests" / "apps" / "check_still_tissue.py").string(),
                                      (root / "out").string()};
    check.insert(check.end(), s.still.begin(), s.still.end());
    const CommandResult result = run_command(check);
    EXPECT_EQ(result.exit_code, 0) << s.file << ":\n" << result.out << result.err;
    std::printf("%s:\n%s", s.file, result.out.c_str());
    fs::remove_all(root);
  }
}
