// What the caches a run keeps across runs share (the anatomy cache, the reference cache): keys
// that change with any bit of a setting, a lock per key so that concurrent processes build an
// entry once, and reading an entry whole.
#pragma once

#include "core/settings_declaration.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>

namespace phantasm {

/// An exclusive flock on a key's lock file, held for the object's life: the first process that
/// needs an entry builds it while the others wait, polling so that a cancelled run stops waiting.
/// On a filesystem without flock it locks nothing (each process then builds the entry itself;
/// the atomic rename keeps every entry whole).
class CacheKeyLock {
public:
  /// @param what names the cache in errors ("anatomy cache")
  /// @throws InputError when the lock file cannot be opened
  /// @throws Cancelled when cancellation is requested while waiting
  CacheKeyLock(const std::filesystem::path& path, const std::string& what);
  ~CacheKeyLock();
  CacheKeyLock(const CacheKeyLock&) = delete;
  CacheKeyLock& operator=(const CacheKeyLock&) = delete;

private:
  int m_fd = -1;
};

/// The whole of a file's bytes (empty when it cannot be read).
std::string read_cache_entry(const std::filesystem::path& path);

} // namespace phantasm
