// The atlas labels cache: label volumes derived from an atlas (atlas/atlas_labels.hpp) kept in the
// anatomy cache's folder, so that the subjects of a sweep over an atlas anatomy derive them once.
#pragma once

#include "atlas/atlas_labels.hpp"
#include "core/progress.hpp"

#include <filesystem>
#include <string>

namespace phantasm {

/// The content hash (SHA-256, hex) that names an atlas's derived labels: the atlas, its templates
/// folder, the bytes of its input files and the build id of the code. Empty when the code has no
/// build id or an input cannot be read (then nothing is kept: the derivation names what is missing).
std::string atlas_labels_cache_key(const std::string& atlas, const std::filesystem::path& templates_dir);

/// The bytes of an entry after its header, and back; decoding throws DamagedBytes for bytes that
/// do not hold derived labels.
std::string encode_atlas_labels(const AtlasLabels& labels);
AtlasLabels decode_atlas_labels(std::string_view bytes);

/// derive_atlas_labels() through a cache folder: the labels stored under their key are read (bit
/// for bit what deriving gives, the provenance lines included), else derived and stored
/// (atomically, once for processes that need them at once). A damaged entry is derived again,
/// with a warning. @param folder empty: no cache, derive_atlas_labels() alone
AtlasLabels
derive_atlas_labels_cached(const std::string& atlas, const std::filesystem::path& folder, Reporter& reporter,
                           const std::filesystem::path& templates_dir = default_colin27_templates_dir());

} // namespace phantasm
