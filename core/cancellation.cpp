#include "core/cancellation.hpp"

#include "core/abandonable_work.hpp"
#include "core/error.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace phantasm {
namespace {
// A lock-free atomic is async-signal-safe; volatile sig_atomic_t would not be thread-safe.
std::atomic<bool> g_cancel_requested{false};
std::atomic<int> g_cancel_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free);
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void on_signal_then_default(int signal_number) {
  request_cancellation(signal_number);
  // A second signal ends the program at once.
  std::signal(signal_number, SIG_DFL);
}

extern "C" void on_signal(int signal_number) {
  request_cancellation(signal_number);
}

std::atomic<int> g_abandonable_depth{0};

/// The temporary files being written (RegisteredTemporary), and the lock that keeps the
/// watchdog from ending the process between a rename and the forgetting of its temporary.
std::mutex& temporaries_mutex() {
  static std::mutex mutex;
  return mutex;
}
std::vector<std::string>& temporaries() {
  static std::vector<std::string> paths;
  return paths;
}
/// Forgets a registered temporary (the caller holds temporaries_mutex()).
void forget_temporary(const std::string& path) {
  auto& paths = temporaries();
  const auto it = std::find(paths.begin(), paths.end(), path);
  if (it != paths.end()) paths.erase(it);
}

/// Waits for a cancellation; if 0.5 s later the process is inside abandonable work (which
/// should have thrown by then), ends it (AbandonableWork). Polls every 20 ms: a sleeping thread.
void watch_cancellation() {
  using namespace std::chrono_literals;
  while (!cancellation_requested())
    std::this_thread::sleep_for(20ms);
  std::this_thread::sleep_for(500ms);
  while (true) {
    if (g_abandonable_depth.load() > 0) {
      // Held until the end: no temporary is renamed or registered after this.
      temporaries_mutex().lock();
      for (const std::string& path : temporaries())
        ::unlink(path.c_str());
      static const char message[] = "\nphantasm: interrupted; every file written so far is complete\n";
      [[maybe_unused]] const ssize_t ignored = ::write(STDERR_FILENO, message, sizeof message - 1);
      const int signal_number = cancellation_signal();
      ::_exit(128 + (signal_number > 0 ? signal_number : SIGINT));
    }
    std::this_thread::sleep_for(20ms);
  }
}
} // namespace

void request_cancellation(int signal_number) noexcept {
  int none = 0;
  if (signal_number != 0) g_cancel_signal.compare_exchange_strong(none, signal_number);
  g_cancel_requested.store(true, std::memory_order_relaxed);
}

namespace {
// The flag of the innermost StopThisThreadWhen on this thread; null outside one.
thread_local const std::atomic<bool>* t_stop_this_thread = nullptr;
} // namespace

bool cancellation_requested() noexcept {
  return g_cancel_requested.load(std::memory_order_relaxed) ||
         (t_stop_this_thread != nullptr && t_stop_this_thread->load(std::memory_order_relaxed));
}

StopThisThreadWhen::StopThisThreadWhen(const std::atomic<bool>& stop) noexcept
    : m_previous(t_stop_this_thread) {
  t_stop_this_thread = &stop;
}

StopThisThreadWhen::~StopThisThreadWhen() {
  t_stop_this_thread = m_previous;
}

StopOnFailure::StopOnFailure(std::atomic<bool>& stop) noexcept
    : m_stop(stop), m_exceptions(std::uncaught_exceptions()) {}

StopOnFailure::~StopOnFailure() {
  if (std::uncaught_exceptions() > m_exceptions) m_stop.store(true, std::memory_order_relaxed);
}

int cancellation_signal() noexcept {
  return g_cancel_signal.load(std::memory_order_relaxed);
}

void throw_if_cancelled() {
  if (cancellation_requested()) throw Cancelled();
}

std::atomic<bool>& cancellation_flag() noexcept {
  return g_cancel_requested;
}

void install_cancellation_handlers(bool second_signal_ends) {
  struct sigaction action {};
  action.sa_handler = second_signal_ends ? on_signal_then_default : on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART; // a signal must not fail a read or write with EINTR
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  std::thread(watch_cancellation).detach();
}

AbandonableWork::AbandonableWork() noexcept {
  g_abandonable_depth.fetch_add(1);
}

AbandonableWork::~AbandonableWork() {
  g_abandonable_depth.fetch_sub(1);
}

RegisteredTemporary::RegisteredTemporary(std::filesystem::path path) : m_path(std::move(path)) {
  const std::lock_guard<std::mutex> lock(temporaries_mutex());
  temporaries().push_back(m_path.string());
  m_registered = true;
}

RegisteredTemporary::~RegisteredTemporary() {
  if (!m_registered) return;
  const std::lock_guard<std::mutex> lock(temporaries_mutex());
  forget_temporary(m_path.string());
}

int RegisteredTemporary::rename_to(const std::filesystem::path& final_path) {
  const std::lock_guard<std::mutex> lock(temporaries_mutex());
  if (std::rename(m_path.c_str(), final_path.c_str()) != 0) return errno != 0 ? errno : EIO;
  forget_temporary(m_path.string());
  m_registered = false;
  return 0;
}

void reset_cancellation() noexcept {
  g_cancel_requested.store(false, std::memory_order_relaxed);
  g_cancel_signal.store(0, std::memory_order_relaxed);
}

} // namespace phantasm
