// The reference session's files kept across runs: a subject's ses-ref images, maps, labels,
// fractions and meshes are the same bytes in every subject that shares the reference state (and,
// for the images and maps, the MRI settings), so the first subject's written bytes are stored
// beside the reference cache's entries and later subjects copy them instead of compressing the
// same volumes again.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace phantasm {

class Reporter;

/// Makes a file's bytes at the path it is given (atomically, as every dataset writer does).
using FileWriter = std::function<void(const std::filesystem::path&)>;

/// `write` through a cache folder, for a file whose bytes follow from `key` and `role` alone:
/// when the folder holds bytes stored under them, they are written to the path (atomically)
/// instead of calling `write`; else `write` makes the file and its bytes are stored (atomically,
/// with deflate's checksums) for the next run. Processes that store the same entry at once store
/// the same bytes. Stored bytes that are damaged are not copied: the file is made again and
/// stored anew, with a warning.
/// @param folder the cache folder (it exists: the reference cache made it); empty: `write` alone
/// @param key the cache key the file's bytes follow from (reference_cache_key,
///        reference_images_key); empty: `write` alone
/// @param role what the file is, the same in every subject (its path in the dataset without the
///        subject: "sub-/ses-ref/anat/sub-_ses-ref_T1w.nii.gz")
FileWriter write_through_cache(const std::filesystem::path& folder, const std::string& key,
                               const std::string& role, FileWriter write, Reporter& reporter);

} // namespace phantasm
