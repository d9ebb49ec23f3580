// Work that writes nothing (the stages before any file is written) may be abandoned: when a
// cancellation is not honoured quickly (CGAL's mesher moving a million vertices in one call
// polls nothing for seconds), the watchdog of install_cancellation_handlers() ends the process.
#pragma once

namespace phantasm {

/// Marks, while it lives, work that neither writes nor holds anything another process could
/// see half-done. If cancellation was requested and 0.5 s later the process is still inside
/// such work, the watchdog started by install_cancellation_handlers() prints the interrupted
/// message and ends the process at once with 128 + signal (no file is open for writing, so
/// nothing half-written is left). Without that watchdog (tests, the Python module) it does
/// nothing: the work stops at its next poll.
class AbandonableWork {
public:
  AbandonableWork() noexcept;
  ~AbandonableWork();
  AbandonableWork(const AbandonableWork&) = delete;
  AbandonableWork& operator=(const AbandonableWork&) = delete;
};

} // namespace phantasm
