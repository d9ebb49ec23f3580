#include "pipeline/reference_files_cache.hpp"

#include "core/byte_codec.hpp"
#include "core/progress.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/byte_compression.hpp"
#include "pipeline/cache_entry.hpp"

#include <string_view>
#include <utility>

namespace phantasm {
namespace {

// The file's first line; the entry's name follows on the second, the file's bytes after it. The
// format number is also part of the entry's name.
constexpr const char* k_file_magic = "phantasm reference file cache 1\n";

} // namespace

FileWriter write_through_cache(const std::filesystem::path& folder, const std::string& key,
                               const std::string& role, FileWriter write, Reporter& reporter) {
  if (folder.empty() || key.empty()) return write;
  const std::string name = sha256_hex(std::string(k_file_magic) + key + "\n" + role);
  return [entry = folder / ("file-" + name + ".bin"), header = std::string(k_file_magic) + name + "\n",
          write = std::move(write), &reporter](const std::filesystem::path& path) {
    const std::string stored = read_cache_entry(entry);
    if (!stored.empty()) {
      try {
        if (stored.compare(0, header.size(), header) != 0) throw DamagedBytes("another key or format");
        // The file's bytes are not compressed again: they are (level 0 keeps deflate's checks).
        write_file_atomically(path, decompress_bytes(std::string_view(stored).substr(header.size())));
        return;
      } catch (const DamagedBytes& damaged) {
        reporter.warning("writing", entry.string() + ": a damaged reference file cache entry (" +
                                        damaged.what() + "); " + path.filename().string() + " made again");
      }
    }
    write(path);
    const std::string bytes = read_cache_entry(path);
    if (!bytes.empty()) write_file_atomically(entry, header + compress_bytes(bytes, 0));
  };
}

} // namespace phantasm
