// Work that writes nothing (the stages before any file is written, a mesh encoded in memory) may
// be abandoned: when a cancellation is not honoured quickly (CGAL's mesher moving a million
// vertices in one call, VTK encoding a million triangles, OpenVDB compressing its grids: none
// polls), the watchdog of install_cancellation_handlers() ends the process. Temporary files
// being written are registered, and the watchdog removes them before it ends the process.
#pragma once

#include <filesystem>

namespace phantasm {

/// Marks, while it lives, work that neither writes nor holds anything another process could
/// see half-done. If cancellation was requested and 0.5 s later the process is still inside
/// such work (on any thread), the watchdog started by install_cancellation_handlers() removes
/// every registered temporary file (RegisteredTemporary), prints the interrupted message and
/// ends the process at once with 128 + signal: every file under a final name is complete, and
/// no temporary is left. Without that watchdog (tests, the Python module) it does nothing: the
/// work stops at its next poll.
class AbandonableWork {
public:
  AbandonableWork() noexcept;
  ~AbandonableWork();
  AbandonableWork(const AbandonableWork&) = delete;
  AbandonableWork& operator=(const AbandonableWork&) = delete;
};

/// A temporary file being written (AtomicFileWriter's, OpenVDB's), known to the watchdog while
/// this lives: a process abandoned meanwhile removes it first. The owner removes the file
/// before this is destroyed, or renames it with rename_to().
class RegisteredTemporary {
public:
  explicit RegisteredTemporary(std::filesystem::path path);
  ~RegisteredTemporary();
  RegisteredTemporary(const RegisteredTemporary&) = delete;
  RegisteredTemporary& operator=(const RegisteredTemporary&) = delete;

  /// Renames the temporary file to `final_path` and forgets it, in one step the watchdog cannot
  /// come between (it either removes the temporary before, or finds the final file complete).
  /// @returns 0, or the errno of a failed rename (the file is then still registered)
  int rename_to(const std::filesystem::path& final_path);

private:
  std::filesystem::path m_path;
  bool m_registered = false;
};

} // namespace phantasm
