// Displacement fields in the conventions registration tools write them: ITK/elastix/ANTs,
// Learn2Reg/LUMIR and voxelmorph, MRtrix3 (deformation and displacement) and dipy. Each is
// written from, and read back into, the DisplacementField of registration_metrics.hpp (on the
// fixed grid, a fixed point x lands at x + u(x) in the moving image).
#pragma once

#include "evaluation/registration_metrics.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// How a field's file stores x -> x + u(x) on the fixed grid (docs/benchmark-tasks.md).
enum class FieldConvention {
  itk,                 ///< 5-D (X, Y, Z, 1, 3), u in LPS mm (ITK, elastix/transformix, ANTs)
  learn2reg,           ///< 4-D (X, Y, Z, 3), u in voxels along i, j, k (Learn2Reg, LUMIR, voxelmorph)
  mrtrix_deformation,  ///< 4-D (X, Y, Z, 3), x + u in scanner RAS mm (mrtransform -warp)
  mrtrix_displacement, ///< 4-D (X, Y, Z, 3), u in scanner RAS mm (warpconvert displacement, dipy)
};

/// The convention's name on the command line: itk, learn2reg, mrtrix-deformation,
/// mrtrix-displacement.
std::string to_string(FieldConvention convention);
/// @throws InputError for another name, listing the known ones
FieldConvention field_convention_from_string(const std::string& name, const std::string& option);

/// u in RAS mm at every voxel of the field's grid (i fastest).
std::vector<Eigen::Vector3d> ras_displacements(const DisplacementField& field);
/// The field whose displacements are `ras_mm` (RAS mm, i fastest) on `grid`.
DisplacementField field_from_ras(const ImageGrid& grid, const std::vector<Eigen::Vector3d>& ras_mm);

/// Writes a field in a convention, float32, on the field's grid (the grid's affine in the header).
void write_field(const std::filesystem::path& path, const DisplacementField& field,
                 FieldConvention convention);

/// Reads a field written in a convention, for the fixed grid `fixed` (Learn2Reg files carry any
/// affine, often the identity: the fixed grid places them).
/// @throws InputError naming the file: another layout, another number of voxels than the fixed
/// grid, an integer datatype, a NaN or infinite value (with its voxel)
DisplacementField read_field(const std::filesystem::path& path, FieldConvention convention,
                             const ImageGrid& fixed);

} // namespace phantasm
