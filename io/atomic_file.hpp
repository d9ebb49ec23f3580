// AtomicFileWriter: every output file is written to a temporary file and renamed, so a final
// name only ever holds a complete file; also the removal of a killed run's temporaries.
#pragma once

#include "core/abandonable_work.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string_view>

namespace phantasm {

/// Writes one file so that its final name only ever holds a complete file. Bytes go to a hidden
/// temporary file in the same folder (".<name>.phantasm-tmp-<pid>-<n>-<host>"); commit() flushes it to
/// disk and renames it over the final name. A writer destroyed without commit() (an exception,
/// a cancelled run) removes its temporary file. A killed process can leave a temporary file,
/// but never a partial file under the final name; remove_stale_temporaries() clears those. A
/// process abandoned by its cancellation watchdog removes the temporary first (AbandonableWork).
class AtomicFileWriter {
public:
  /// Creates missing parent folders and opens the temporary file.
  /// @throws std::runtime_error naming the path when the file cannot be created
  explicit AtomicFileWriter(std::filesystem::path final_path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  /// Appends bytes. Checks for cancellation between chunks, so a SIGINT stops a long write.
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Makes the file visible under its final name (fsync of the file, rename, fsync of the folder).
  void commit();

  const std::filesystem::path& final_path() const { return m_final_path; }
  const std::filesystem::path& temporary_path() const { return m_temporary_path; }

private:
  std::filesystem::path m_final_path;
  std::filesystem::path m_temporary_path;
  std::optional<RegisteredTemporary> m_registration;
  int m_fd = -1;
  bool m_committed = false;
};

/// Writes a whole file atomically (see AtomicFileWriter).
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// True for the name of a temporary file made by AtomicFileWriter.
bool is_temporary_file_name(const std::filesystem::path& path);

/// Removes the temporary files a killed run left under a folder; returns how many. Temporary
/// files of processes still running (named by their pid) are theirs and stay, and so are those
/// of other machines (named by their host): on a shared file system their processes are unseen.
std::size_t remove_stale_temporaries(const std::filesystem::path& root);

/// Slows every chunk written by AtomicFileWriter (4 KiB while a delay is set) by this many
/// milliseconds, pauses as long in commit() between closing the temporary file and renaming it,
/// and before every block of an HDF5 export. Only for tests that interrupt a run while it
/// writes; 0 (the default) turns it off.
void set_write_delay_for_testing(int milliseconds_per_chunk);

/// The delay set by set_write_delay_for_testing() (0: none).
int write_delay_for_testing();

} // namespace phantasm
