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

/// A transformix parameter file that applies a displacement field on a grid, the way
/// docs/use-with-your-tools.md tells users to.
std::string transform_parameters(const fs::path& field, const phantasm::ImageGrid& grid) {
  return "(Transform \"DeformationFieldTransform\")\n(DeformationFieldFileName \"" + field.string() +
         "\")\n(DeformationFieldInterpolationOrder 1)\n(NumberOfParameters 0)\n" +
         transformix_grid_lines(grid);
}

fs::path run_transformix(const fs::path& moving, const fs::path& field, const phantasm::ImageGrid& grid,
                         const fs::path& folder) {
  fs::create_directories(folder);
  write_text_file(folder / "parameters.txt", transform_parameters(field, grid));
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
