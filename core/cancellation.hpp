// Cooperative cancellation: a signal handler requests it, and stages check for it inside their
// long loops (and library callbacks: CGAL's domain oracle, OpenVDB's interrupter) so that SIGINT
// or SIGTERM stops a run within a second with nothing left half-written.
#pragma once

#include <atomic>

namespace phantasm {

/// Asks running stages to stop at their next safe point. Safe to call from a signal handler.
/// @param signal_number the signal that asked (SIGINT, SIGTERM), 0 when none; the first one is
///        kept and decides the exit code (128 + signal).
void request_cancellation(int signal_number = 0) noexcept;

/// True once request_cancellation() was called, or on a thread inside a StopThisThreadWhen whose
/// flag is set. Relaxed atomic loads: cheap enough for inner loops (a poll per patch, per voxel
/// slab, per solver iteration).
bool cancellation_requested() noexcept;

/// For its life, makes cancellation_requested() true on the thread that made it (and
/// throw_if_cancelled() throw there) once `stop` is set; other threads are not affected. A
/// helper thread whose result is no longer wanted (the work it runs beside has failed) then ends
/// at its next poll instead of making the caller's error wait for it. Nests: the one made last
/// on a thread is the one asked.
class StopThisThreadWhen {
public:
  explicit StopThisThreadWhen(const std::atomic<bool>& stop) noexcept;
  ~StopThisThreadWhen();
  StopThisThreadWhen(const StopThisThreadWhen&) = delete;
  StopThisThreadWhen& operator=(const StopThisThreadWhen&) = delete;

private:
  const std::atomic<bool>* m_previous;
};

/// Sets `stop` when it is destroyed by an exception's unwinding (not on a normal exit): made
/// after the helper thread's future, it releases the helper before the future waits for it.
class StopOnFailure {
public:
  explicit StopOnFailure(std::atomic<bool>& stop) noexcept;
  ~StopOnFailure();
  StopOnFailure(const StopOnFailure&) = delete;
  StopOnFailure& operator=(const StopOnFailure&) = delete;

private:
  std::atomic<bool>& m_stop;
  int m_exceptions;
};

/// The signal that asked for cancellation, 0 when none was given (or none was requested).
int cancellation_signal() noexcept;

/// Throws phantasm::Cancelled when cancellation was requested; stages call it between units
/// of work so that nothing is left half-written.
void throw_if_cancelled();

/// The flag itself, for libraries that poll an std::atomic<bool> (read it, never store into it).
std::atomic<bool>& cancellation_flag() noexcept;

/// Installs handlers that turn SIGINT and SIGTERM into request_cancellation(signal).
/// @param second_signal_ends true: a second signal ends the process at once (the default action,
///        for a person at a terminal); false: every signal only requests cancellation (a batch's
///        subject, which its batch signals too).
void install_cancellation_handlers(bool second_signal_ends);

/// Clears the request (tests and long-lived processes such as the Python module).
void reset_cancellation() noexcept;

} // namespace phantasm
