// NIfTI files: writing float images, label maps and displacement fields (RAS mm, atomically),
// and reading scalar, vector and label volumes with their grids.
#pragma once

#include "core/grid.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// NIfTI intent codes phantasm writes (nifti1.h).
enum class NiftiIntent : std::int16_t {
  none = 0,
  label = 1002,        ///< label maps
  displacement = 1007, ///< vector displacement fields
};

/// What a NIfTI file stores, besides its grid.
struct NiftiWriteOptions {
  NiftiIntent intent = NiftiIntent::none;
  int components = 1;      ///< 1 for scalar images; 3 for vector fields (dim [5, X, Y, Z, 1, 3])
  std::string description; ///< the header's descrip field (at most 79 characters kept)
  /// Vector components along the fourth dimension (dim [4, X, Y, Z, 3]), as nibabel saves an
  /// (X, Y, Z, 3) array: the layout of Learn2Reg, MRtrix3, voxelmorph and dipy fields.
  bool components_in_fourth_dimension = false;
};

/// Writes a NIfTI-1 image (float32), gzip-compressed when the path ends in ".gz", atomically
/// (temporary file, then rename). The grid's world_from_voxel becomes both the qform and the
/// sform (code 1, scanner anatomical) in RAS mm; xyzt_units are mm and seconds.
/// values: grid.voxel_count() * components values, i fastest, then j, k, then the component.
/// @throws std::invalid_argument when the value count does not match the grid
void write_nifti(const std::filesystem::path& path, const ImageGrid& grid, const std::vector<float>& values,
                 const NiftiWriteOptions& options = {});

/// Writes a scalar image as NIfTI-1 of whole numbers, int16 or uint16, as scanners write them:
/// each value rounded to the nearest and clamped to the type's range (NaN as 0).
/// @throws std::invalid_argument when the value count does not match the grid
void write_nifti_whole_numbers(const std::filesystem::path& path, const ImageGrid& grid,
                               const std::vector<float>& values, bool is_signed,
                               const NiftiWriteOptions& options = {});

/// Writes a label map as NIfTI-1, datatype uint8 when every label fits, else int16 or int32
/// (intent label unless the options say otherwise).
void write_nifti_labels(const std::filesystem::path& path, const ImageGrid& grid,
                        const std::vector<std::int32_t>& labels, const NiftiWriteOptions& options = {});

/// A scalar volume read from a NIfTI file.
struct NiftiVolume {
  ImageGrid grid;
  std::vector<double> values; ///< grid.voxel_count() values per component, i fastest
  int datatype = 0;           ///< NIfTI datatype code of the file
};

/// Reads a 3-D NIfTI-1 or NIfTI-2 file (.nii or .nii.gz). The grid comes from the sform when
/// its code is positive, else the qform, else the voxel sizes alone; scaling (scl_slope,
/// scl_inter) is applied.
/// @throws InputError naming the file when it is missing, unreadable, not 3-D, or has
/// a shear (phantasm grids are rotations times spacings)
NiftiVolume read_nifti(const std::filesystem::path& path);

/// Reads a vector image in the ITK convention, 5-D (X, Y, Z, 1, components), e.g. a
/// displacement field (components = 3, as phantasm, elastix and transformix write them). The
/// values come component by component: all voxels' first component, then the second, ...
/// @throws InputError naming the file as read_nifti, and for any other layout (a 4-D
/// (X, Y, Z, 3) file is named as such: ITK would read it as a time series)
NiftiVolume read_nifti_vectors(const std::filesystem::path& path, int components = 3);

/// Reads a vector image with its components along the fourth dimension, 4-D (X, Y, Z,
/// components), as nibabel saves an (X, Y, Z, 3) array; values ordered as read_nifti_vectors.
/// @throws InputError naming the file as read_nifti, and for any other layout
NiftiVolume read_nifti_vectors_4d(const std::filesystem::path& path, int components = 3);

/// Reads a label volume: a NIfTI file of integer labels (an integer datatype, or floats that
/// are all whole numbers).
/// @throws InputError as read_nifti, and naming the first voxel that is not a whole number
std::vector<std::int32_t> read_nifti_labels(const std::filesystem::path& path, ImageGrid* grid);

/// Pauses this many milliseconds before every piece (1 MiB) of voxels the read functions read
/// (a gzipped file then goes through zlib's stream, in those pieces, rather than being inflated
/// a gzip member at a time). Only for tests that interrupt a command while it reads; 0 (the
/// default) turns it off.
void set_read_delay_for_testing(int milliseconds_per_piece);

/// Whether gzipped voxels are inflated a gzip member at a time by libdeflate (true, the
/// default) or read through zlib's stream in pieces: for tests and benchmarks that compare them.
void set_whole_member_reads_for_testing(bool enabled);

/// How many gzipped files this process has read by inflating their members whole (libdeflate),
/// for tests that check a file took that way.
std::size_t whole_member_reads_for_testing();

} // namespace phantasm
