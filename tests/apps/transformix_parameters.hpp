#pragma once

// transformix parameter files for tests that hand phantasm's grids and fields to Debian's
// transformix (ITK conventions: origin and direction in LPS; elastix lists the direction matrix
// column by column).

#include "core/grid.hpp"

#include <filesystem>
#include <sstream>
#include <string>

namespace phantasm::testing {

/// The lines of a transformix parameter file that place the output on `grid`, with
/// nearest-neighbour resampling (FinalBSplineInterpolator of order 0) into short NIfTI.
inline std::string transformix_grid_lines(const ImageGrid& grid) {
  const Eigen::Matrix3d ras_to_lps = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  const Eigen::Vector3d origin = ras_to_lps * grid.world_from_voxel.topRightCorner<3, 1>();
  const Eigen::Matrix3d direction =
      ras_to_lps * grid.world_from_voxel.topLeftCorner<3, 3>() * grid.spacing_mm.cwiseInverse().asDiagonal();
  std::ostringstream p;
  p.precision(17);
  p << "(InitialTransformParametersFileName \"NoInitialTransform\")\n(HowToCombineTransforms \"Compose\")\n"
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

/// A transformix parameter file that applies a displacement field on a grid, the way
/// docs/use-with-your-tools.md tells users to.
inline std::string deformation_field_parameters(const std::filesystem::path& field, const ImageGrid& grid) {
  return "(Transform \"DeformationFieldTransform\")\n(DeformationFieldFileName \"" + field.string() +
         "\")\n(DeformationFieldInterpolationOrder 1)\n(NumberOfParameters 0)\n" +
         transformix_grid_lines(grid);
}

} // namespace phantasm::testing
