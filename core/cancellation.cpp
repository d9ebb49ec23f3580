#include "core/cancellation.hpp"

#include "core/error.hpp"

#include <atomic>
#include <csignal>

namespace phantasm {
namespace {
// A lock-free atomic is async-signal-safe; volatile sig_atomic_t would not be thread-safe.
std::atomic<bool> g_cancel_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free);
} // namespace

void request_cancellation() noexcept {
  g_cancel_requested.store(true, std::memory_order_relaxed);
}

bool cancellation_requested() noexcept {
  return g_cancel_requested.load(std::memory_order_relaxed);
}

void throw_if_cancelled() {
  if (cancellation_requested()) throw Cancelled();
}

void reset_cancellation() noexcept {
  g_cancel_requested.store(false, std::memory_order_relaxed);
}

} // namespace phantasm
