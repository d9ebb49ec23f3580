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
/// machine-learning loaders. For every complete subject (provenance.json present), every file its
/// provenance lists that the dataset layout names:
///   /sub-<id>/ses-<ref|def>/<suffix>           images, float32 (X, Y, Z)
///   /sub-<id>/ses-<ref|def>/dseg               labels, int32 (X, Y, Z)
///   /sub-<id>/ses-<ref|def>/probseg/<tissue>   fractions 0-1, float32 (X, Y, Z)
///   /sub-<id>/ses-<ref|def>/maps/<suffix>      parameter maps (PDmap, T1map, ...), float32 (X, Y, Z)
///   /sub-<id>/ses-<ref|def>/landmarks          float64 (N, 3) RAS mm; attributes names, organs
///   /sub-<id>/xfm/<file name less subject>     for each direction (from-def_to-ref,
///                                              from-ref_to-def): the field, float32 (X, Y, Z, 3)
///                                              in LPS mm (the NIfTI file's (X, Y, Z, 1, 3)); its
///                                              exact mask, uint8; its Jacobian, float32
/// Arrays are indexed (i, j, k[, component]) like nibabel's get_fdata(), chunked and
/// gzip-compressed. Metadata are attributes: each array's kind, units (a sidecar's "Units" when it
/// has one), frame, axes, source file, affine (4 x 4, RAS mm) and JSON sidecar; each subject's
/// provenance and participants.tsv values; the file's label table (dseg.tsv) and conventions.
/// Written to a temporary file and renamed, so the final name only ever holds a complete file.
/// @throws InputError when the folder holds no complete subject
Hdf5ExportSummary export_hdf5(const std::filesystem::path& dataset, const std::filesystem::path& file,
                              const Hdf5ExportOptions& options,
                              const std::function<void(const std::string&)>& progress = {});

} // namespace phantasm
