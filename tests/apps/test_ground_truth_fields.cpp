// The ground-truth fields of `phantasm run`, checked by real clients: Debian's transformix applies
// each field to the other state's label map (nearest neighbour: FinalBSplineInterpolator of order
// 0), and numpy/scipy composes the two fields (tests/apps/check_fields.py).

#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// A transformix parameter file for a displacement field on a grid (ITK conventions: origin and
/// direction in LPS; elastix lists the direction matrix column by column).
std::string transform_parameters(const fs::path& field, const phantasm::ImageGrid& grid) {
  const Eigen::Matrix3d ras_to_lps = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  const Eigen::Vector3d origin = ras_to_lps * grid.world_from_voxel.topRightCorner<3, 1>();
  const Eigen::Matrix3d direction =
      ras_to_lps * grid.world_from_voxel.topLeftCorner<3, 3>() * grid.spacing_mm.cwiseInverse().asDiagonal();
  std::ostringstream p;
  p.precision(17);
  p << "(Transform \"DeformationFieldTransform\")\n"
    << "(DeformationFieldFileName \"" << field.string() << "\")\n"
    << "(DeformationFieldInterpolationOrder 1)\n(NumberOfParameters 0)\n"
    << "(InitialTransformParametersFileName \"NoInitialTransform\")\n(HowToCombineTransforms \"Compose\")\n"
    << "(FixedImageDimension 3)\n(MovingImageDimension 3)\n"
    << "(FixedInternalImagePixelType \"float\")\n(MovingInternalImagePixelType \"float\")\n"
    << "(Size " << grid.dims.x() << ' ' << grid.dims.y() << ' ' << grid.dims.z() << ")\n(Index 0 0 0)\n"
    << "(Spacing " << grid.spacing_mm.x() << ' ' << grid.spacing_mm.y() << ' ' << grid.spacing_mm.z() << ")\n"
    << "(Origin " << origin.x() << ' ' << origin.y() << ' ' << origin.z() << ")\n(Direction";
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      p << ' ' << direction(r, c);
  p << ")\n(UseDirectionCosines \"true\")\n"
    << "(ResampleInterpolator \"FinalBSplineInterpolator\")\n(FinalBSplineInterpolationOrder 0)\n"
    << "(Resampler \"DefaultResampler\")\n(DefaultPixelValue 0)\n"
    << "(ResultImageFormat \"nii.gz\")\n(ResultImagePixelType \"short\")\n(CompressResultImage \"true\")\n";
  return p.str();
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

TEST(GroundTruthFields, TransformixResamplesEachStateOntoTheOtherAndTheFieldsInvertEachOther) {
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

  const fs::path forward =
      run_transformix(sub / "ses-def" / "anat" / "sub-01_ses-def_dseg.nii.gz",
                      sub / "xfm" / "sub-01_from-ref_to-def_mode-image_xfm.nii.gz", grid, root / "forward");
  const fs::path backward =
      run_transformix(sub / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz",
                      sub / "xfm" / "sub-01_from-def_to-ref_mode-image_xfm.nii.gz", grid, root / "backward");
  const CommandResult check =
      run_command({PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_fields.py").string(),
                   out.string(), forward.string(), backward.string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  std::printf("%s", check.out.c_str());
}
