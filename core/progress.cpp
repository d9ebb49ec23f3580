#include "core/progress.hpp"

#include "core/cancellation.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <iostream>
#include <sstream>

namespace phantasm {

ProgressStyle progress_style_for(int file_descriptor, bool quiet) {
  if (quiet) return ProgressStyle::none;
  return ::isatty(file_descriptor) ? ProgressStyle::bar : ProgressStyle::lines;
}

Reporter::Reporter(std::ostream& stream, ProgressStyle style) : m_stream(&stream), m_style(style) {}

Reporter Reporter::silent() {
  return Reporter(std::cerr, ProgressStyle::none);
}

void Reporter::modelled(const std::string& stage, const std::string& message) {
  std::string line = "[" + stage + "] " + message;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_log.push_back(line);
  }
  print(line);
}

void Reporter::skipped(const std::string& stage, const std::string& message) {
  modelled(stage, "skipped: " + message);
}

void Reporter::warning(const std::string& stage, const std::string& message) {
  const std::string line = "[" + stage + "] warning: " + message;
  std::lock_guard<std::mutex> lock(m_mutex);
  m_log.push_back(line);
  write_line(line);
}

void Reporter::note(const std::string& message) {
  print(message);
}

void Reporter::print(const std::string& line) {
  if (m_style == ProgressStyle::none) return;
  std::lock_guard<std::mutex> lock(m_mutex);
  write_line(line);
}

void Reporter::write_line(const std::string& line) {
  // A bar redrawn with '\r' has no newline until it finishes: a line printed after it would run
  // on after the bar. Clear the bar's line first (the bar redraws below on its next step).
  if (m_bar_on_line) (*m_stream) << "\r\033[K";
  m_bar_on_line = false;
  (*m_stream) << line << '\n' << std::flush;
}

namespace {

/// The innermost living bar: progress_detail() reaches it without being handed it.
std::atomic<ProgressBar*> g_innermost{nullptr};
/// When a detail was last set (steady clock, ns): progress_detail_due() reads it lock-free.
std::atomic<std::int64_t> g_last_detail_ns{0};

/// A plain line at most this often (a pipe or a log file).
constexpr auto k_line_interval = std::chrono::seconds(5);
/// The bar is redrawn at most this often on advance(), and at least this often by the ticker.
constexpr auto k_redraw_interval = std::chrono::milliseconds(100);
constexpr auto k_tick_interval = std::chrono::seconds(1);
constexpr std::size_t k_max_detail = 70; ///< characters of detail kept on the line

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// "42.1 s", "3 min 20 s", "1 h 05 min".
std::string format_duration(double seconds) {
  char text[32];
  if (seconds < 100.0) {
    std::snprintf(text, sizeof text, "%.1f s", seconds);
  } else if (seconds < 3600.0) {
    const int s = static_cast<int>(seconds);
    std::snprintf(text, sizeof text, "%d min %02d s", s / 60, s % 60);
  } else {
    const int m = static_cast<int>(seconds / 60.0);
    std::snprintf(text, sizeof text, "%d h %02d min", m / 60, m % 60);
  }
  return text;
}

/// This thread's details go nowhere (QuietProgressDetails).
thread_local bool t_quiet_details = false;

} // namespace

QuietProgressDetails::QuietProgressDetails() : m_was_quiet(t_quiet_details) {
  t_quiet_details = true;
}

QuietProgressDetails::~QuietProgressDetails() {
  t_quiet_details = m_was_quiet;
}

void progress_detail(std::string detail) {
  if (t_quiet_details) return;
  g_last_detail_ns.store(now_ns(), std::memory_order_relaxed);
  if (ProgressBar* bar = g_innermost.load()) bar->set_detail(std::move(detail));
}

bool progress_detail_due() noexcept {
  if (t_quiet_details || g_innermost.load(std::memory_order_relaxed) == nullptr) return false;
  return now_ns() - g_last_detail_ns.load(std::memory_order_relaxed) >= 200'000'000;
}

ProgressBar::ProgressBar(Reporter& reporter, std::string label, std::size_t total)
    : m_reporter(reporter), m_label(std::move(label)), m_total(total == 0 ? 1 : total),
      m_start(std::chrono::steady_clock::now()), m_last_draw(m_start),
      m_uncaught_exceptions(std::uncaught_exceptions()) {
  m_outer = g_innermost.exchange(this);
  start_ticker();
}

ProgressBar::ProgressBar(Reporter& reporter, std::string label, std::size_t total, Unlisted)
    : m_reporter(reporter), m_label(std::move(label)), m_total(total == 0 ? 1 : total),
      m_start(std::chrono::steady_clock::now()), m_last_draw(m_start),
      m_uncaught_exceptions(std::uncaught_exceptions()), m_listed(false) {
  start_ticker();
}

void ProgressBar::start_ticker() {
  if (m_reporter.m_style == ProgressStyle::none) return;
  m_ticker = std::thread([this] {
    std::unique_lock<std::mutex> lock(m_mutex);
    while (!m_stop_ticker) {
      m_wake.wait_for(lock, k_tick_interval);
      if (m_stop_ticker) break;
      lock.unlock();
      const std::size_t done = m_done.load();
      draw(done < m_total ? done : m_total, false, true);
      lock.lock();
    }
  });
}

ProgressBar::~ProgressBar() {
  if (std::uncaught_exceptions() > m_uncaught_exceptions && !m_finished) {
    // Unwinding (a cancellation, an error): end the line where the work stopped, not at 100 %.
    stop_ticker();
    const std::size_t done = m_done.load();
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_detail = "stopped";
    }
    draw(done < m_total ? done : m_total, true);
    notify(done < m_total ? done : m_total, true);
    m_finished = true;
  } else {
    finish();
  }
  if (m_listed) g_innermost.store(m_outer);
}

void ProgressBar::stop_ticker() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop_ticker = true;
  }
  m_wake.notify_all();
  if (m_ticker.joinable()) m_ticker.join();
}

void ProgressBar::advance(std::size_t steps) {
  const std::size_t done = m_done.fetch_add(steps) + steps;
  draw(done < m_total ? done : m_total, false);
  notify(done < m_total ? done : m_total, false);
}

void ProgressBar::notify(std::size_t done, bool final) {
  if (!m_reporter.m_callback) return;
  if (!final) {
    // At most every 100 ms: one caller wins the slot, the others return at once.
    const std::int64_t now = now_ns();
    std::int64_t last = m_last_notify_ns.load(std::memory_order_relaxed);
    if (now - last < 100'000'000) return;
    if (!m_last_notify_ns.compare_exchange_strong(last, now)) return;
  }
  std::string detail;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    detail = m_detail;
  }
  try {
    m_reporter.m_callback(m_label, static_cast<double>(done) / static_cast<double>(m_total), detail);
  } catch (...) {
    // Stages advance bars inside parallel loops, where an exception may not pass: stop instead.
    request_cancellation();
  }
}

void ProgressBar::set_detail(std::string detail) {
  if (detail.size() > k_max_detail) detail = detail.substr(0, k_max_detail - 3) + "...";
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_detail = std::move(detail);
  }
  const std::size_t done = m_done.load();
  draw(done < m_total ? done : m_total, false);
  notify(done < m_total ? done : m_total, false);
}

void ProgressBar::finish() {
  if (m_finished) return;
  stop_ticker();
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_detail.clear();
  }
  draw(m_total, true);
  notify(m_total, true);
  m_finished = true;
}

void ProgressBar::draw(std::size_t done, bool final, bool tick) {
  if (m_reporter.m_style == ProgressStyle::none) return;
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_finished) return;
  const auto now = std::chrono::steady_clock::now();
  const bool bar = m_reporter.m_style == ProgressStyle::bar;
  if (!final) {
    // A bar redraws at most every 100 ms (more often costs more than it tells); plain lines
    // come at most every few seconds, so a log stays readable.
    if (bar && !tick && now - m_last_draw < k_redraw_interval) return;
    if (!bar && now - m_last_draw < k_line_interval) return;
  }
  m_last_draw = now;
  const double seconds = std::chrono::duration<double>(now - m_start).count();
  const double fraction = static_cast<double>(done) / static_cast<double>(m_total);
  char counts[64];
  std::snprintf(counts, sizeof counts, " %3d%% (%zu/%zu) ", static_cast<int>(100.0 * fraction), done,
                m_total);
  std::string tail = counts + format_duration(seconds);
  // The time left, from the mean time per unit so far (once a unit is done and some remain).
  if (!final && done > 0 && done < m_total) {
    const double left = seconds * static_cast<double>(m_total - done) / static_cast<double>(done);
    tail += ", about " + format_duration(left) + " left";
  }
  if (!m_detail.empty()) tail += ": " + m_detail;

  std::ostringstream text;
  if (bar) {
    constexpr int width = 30;
    const int filled = static_cast<int>(fraction * width);
    // \r and clear to the end of the line: one line, redrawn in place, whatever its length was.
    text << '\r' << m_label << " [" << std::string(filled, '#') << std::string(width - filled, '-') << ']'
         << tail << "\033[K";
    if (final) text << '\n';
  } else {
    text << m_label << tail << '\n';
  }
  std::lock_guard<std::mutex> print_lock(m_reporter.m_mutex);
  (*m_reporter.m_stream) << text.str() << std::flush;
  m_reporter.m_bar_on_line = m_reporter.m_style == ProgressStyle::bar && !final;
}

} // namespace phantasm
