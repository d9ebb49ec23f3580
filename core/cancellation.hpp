// Cooperative cancellation: a signal handler requests it, and stages check for it between units
// of work so that SIGINT or SIGTERM stops a run with nothing left half-written.
#pragma once

namespace phantasm {

/// Asks running stages to stop at their next safe point. Safe to call from a signal handler.
void request_cancellation() noexcept;

/// True once request_cancellation() was called.
bool cancellation_requested() noexcept;

/// Throws phantasm::Cancelled when cancellation was requested; stages call it between units
/// of work so that nothing is left half-written.
void throw_if_cancelled();

/// Clears the request (tests and long-lived processes such as the Python module).
void reset_cancellation() noexcept;

} // namespace phantasm
