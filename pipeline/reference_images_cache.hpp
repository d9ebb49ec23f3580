// The reference images cache: the reference state's MR images and parameter maps stored under
// the content hash of everything that makes them, so that the subjects of a sweep that share
// the reference state and the MRI settings and differ in the deformation synthesize only the
// deformed state's images.
#pragma once

#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "mri/mri_settings.hpp"
#include "mri/synthesize_images.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace phantasm {

/// The content hash (SHA-256, hex) that names a reference state's images: the reference state's
/// key (reference_cache_key: the anatomy, the grid, the voxelization, the organ table, the build
/// id) and every MRI setting the reference images and maps are made from: the field strength,
/// the tissue values, the sequences (every field, in order: an image's noise is seeded by its
/// index), the acquisition (k-space, coils, noise, bias), the seed, whether parameter maps are
/// made, and the entry's format. What only the deformed state or the outputs read (the
/// deformation, the output flags) leaves it unchanged. Empty when the reference key is.
std::string reference_images_key(const std::string& reference_key, const MriSettings& mri);

/// Reference images and maps as bytes: each image's noise sigma and magnitudes (stored as they
/// are, with deflate's checks: noisy floats do not compress), the maps compressed.
std::string encode_reference_images(const ReferenceImages& images);

/// The images and maps of encode_reference_images() bytes.
/// @param sequences the images expected (one per sequence)
/// @param maps whether parameter maps are expected
/// @param voxels the grid's voxel count: every image and map holds as many values
/// @throws DamagedBytes when the bytes do not hold that
ReferenceImages decode_reference_images(std::string_view bytes, std::size_t sequences, bool maps,
                                        std::size_t voxels);

/// synthesize_images() through a cache folder: the reference state's images and maps stored under
/// the key of these inputs are read when there, else made (the reference state alone) and stored
/// atomically; then the deformed state's are synthesized. Processes that need the same key at
/// once make it once: the others wait on the key's lock file (cancellable) while the first makes
/// the reference images, and read what it stored. A damaged entry is made again, with a warning.
/// The entry's line goes to the report (the same whether the images were made or read); which it
/// was, to the screen. The result is bit for bit that of synthesize_images().
/// @param reference_key the reference state's reference_cache_key(); empty: no cache
/// @param folder the cache folder (made when missing); empty: no cache, synthesize_images() alone
MrImages synthesize_images_cached(const std::string& reference_key, const MriSettings& mri,
                                  const OrganTable& organs, const VoxelizedPhantom& volumes,
                                  const std::filesystem::path& folder, StageReport& report,
                                  Reporter& reporter);

} // namespace phantasm
