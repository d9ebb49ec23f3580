// The anatomy cache: a built phantom stored under the content hash of everything that made it,
// so that runs and batch subjects with the same anatomy fit and mesh it once.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "anatomy/organ.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"

#include <filesystem>
#include <map>
#include <string>

namespace phantasm {

/// The content hash (SHA-256, hex) that names a built anatomy: the anatomy settings (every
/// field, the seed included), the shape data read from files or derived from atlases (their
/// bytes), the encoding's format and the build id of the code. Empty when the code has no build
/// id (nothing may then be kept across runs).
std::string anatomy_cache_key(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files);

/// build_phantom() through a cache folder: the phantom stored under the key of these settings
/// and files is read when there (bit for bit what building gives), else built and stored
/// (atomically). Processes that need the same key at once build it once: the others wait on
/// the key's lock file (cancellable) and read what the first stored. A damaged entry is built
/// again, with a warning. What was reused or stored is written to the report and the log.
/// @param folder the cache folder (made when missing); empty: no cache, build_phantom() alone
/// @param key_out receives the entry's key (anatomy_cache_key) when there is a folder, so a caller
///        that needs it too does not hash the settings and files again (tens of MB of labels)
Phantom build_phantom_cached(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                             const std::filesystem::path& folder, StageReport& report, Reporter& reporter,
                             std::string* key_out = nullptr);

} // namespace phantasm
