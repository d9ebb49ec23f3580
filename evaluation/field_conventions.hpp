// Displacement fields in the conventions registration tools write them: ITK/elastix/ANTs,
// Learn2Reg/LUMIR and voxelmorph, MRtrix3 (deformation and displacement) and dipy. Each is
// written from, and read back into, the DisplacementField of registration_metrics.hpp (on the
// fixed grid, a fixed point x lands at x + u(x) in the moving image). Each convention is a member
// of a registry, one per file of evaluation/field_conventions/ (docs/architecture.md, "Adding a
// variant").
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

/// A convention another one's files are mistaken for, and what that reading does to the field.
struct FieldConfusion {
  FieldConvention with;
  const char* mistake; ///< "LPS read as RAS: x and y reversed"
};

/// The fixed grid a field is stored on, with its affine's linear part and inverse computed once.
struct FieldFrame {
  const ImageGrid& grid;
  Eigen::Matrix3d ras_from_index; ///< d(RAS mm) / d(voxel index)
  Eigen::Matrix3d index_from_ras;
  explicit FieldFrame(const ImageGrid& g);
};

/// One field convention of the registry (evaluation/field_conventions/NAME.cpp): how a field's
/// file stores u(x) at each voxel of the fixed grid.
struct FieldConventionType {
  FieldConvention convention;
  const char* name;        ///< on the command line (--convention) and in messages
  const char* description; ///< one line for help and the docs
  /// 4-D (X, Y, Z, 3) NIfTI; false: ITK's 5-D (X, Y, Z, 1, 3)
  bool components_in_fourth_dimension = true;
  /// Its vectors are world mm: a file on another voxel-to-world matrix is another field.
  bool world_frame = true;
  /// What the file holds at voxel `ijk` of the frame's grid for the displacement `ras_mm` (RAS mm).
  Eigen::Vector3d (*stored)(const FieldFrame& frame, const Eigen::Vector3d& ijk,
                            const Eigen::Vector3d& ras_mm) = nullptr;
  /// The displacement (RAS mm) a file's `stored` vector at voxel `ijk` of the frame's grid stands for.
  Eigen::Vector3d (*displacement)(const FieldFrame& frame, const Eigen::Vector3d& ijk,
                                  const Eigen::Vector3d& stored) = nullptr;
  /// The conventions its files are mistaken for.
  std::vector<FieldConfusion> confusions = {};
};

/// Every registered convention, in the docs' order.
const std::vector<const FieldConventionType*>& field_convention_types();

/// The member of a convention (every convention has one).
const FieldConventionType& field_convention_type(FieldConvention convention);

/// The help of a --convention option: the names, the default first.
std::string field_convention_help(FieldConvention default_convention);

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
