// Export of a dataset's complete subjects (images, labels, fields and their metadata) into one
// HDF5 file for machine-learning loaders (`phantasm hdf5`).
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace phantasm {

struct Hdf5ExportOptions {
  int compression = 4; ///< gzip level 0-9
  int chunk = 64;      ///< chunk edge in voxels (chunks are chunk^3, or smaller at small grids)
};

struct Hdf5ExportSummary {
  std::size_t subjects = 0, arrays = 0;
};

/// Exports a dataset (one `phantasm run` or a whole `phantasm batch`) into one HDF5 file for
/// machine-learning loaders: for every complete subject (provenance.json present) its images
/// (/sub-<id>/ses-<ref|def>/<suffix>, float32), labels (/sub-<id>/ses-<ref|def>/dseg, int32)
/// and fields (/sub-<id>/xfm/from-<a>_to-<b>, float32 (X, Y, Z, 3) in LPS mm, with
/// /sub-<id>/xfm/from-<a>_to-<b>_exact_mask and /sub-<id>/xfm/jacobian). Arrays are indexed
/// (i, j, k[, component]) like nibabel's get_fdata(), chunked and gzip-compressed. Metadata are
/// attributes: each array's affine (4 x 4, RAS mm) and JSON sidecar, each subject's provenance
/// and its participants.tsv values, the file's label table (dseg.tsv) and conventions. Written
/// to a temporary file and renamed, so the final name only ever holds a complete file.
/// @throws InputError when the folder holds no complete subject
Hdf5ExportSummary export_hdf5(const std::filesystem::path& dataset, const std::filesystem::path& file,
                              const Hdf5ExportOptions& options,
                              const std::function<void(const std::string&)>& progress = {});

} // namespace phantasm
