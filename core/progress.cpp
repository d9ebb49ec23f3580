#include "core/progress.hpp"

#include <unistd.h>

#include <cstdio>
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

ProgressBar::ProgressBar(Reporter& reporter, std::string label, std::size_t total)
    : m_reporter(reporter), m_label(std::move(label)), m_total(total == 0 ? 1 : total),
      m_start(std::chrono::steady_clock::now()), m_last_draw(m_start) {}

ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::advance(std::size_t steps) {
  const std::size_t done = m_done.fetch_add(steps) + steps;
  draw(done < m_total ? done : m_total, false);
}

void ProgressBar::finish() {
  if (m_finished) return;
  draw(m_total, true);
  m_finished = true;
}

void ProgressBar::draw(std::size_t done, bool final) {
  if (m_reporter.m_style == ProgressStyle::none) return;
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_finished) return;
  const auto now = std::chrono::steady_clock::now();
  const double seconds = std::chrono::duration<double>(now - m_start).count();
  const double fraction = static_cast<double>(done) / static_cast<double>(m_total);
  char tail[64];
  std::snprintf(tail, sizeof tail, " %3d%% (%zu/%zu) %.1f s", static_cast<int>(100.0 * fraction), done,
                m_total, seconds);

  std::ostringstream text;
  if (m_reporter.m_style == ProgressStyle::bar) {
    // Redrawing more often than every 50 ms costs more than it tells.
    if (!final && now - m_last_draw < std::chrono::milliseconds(50)) return;
    m_last_draw = now;
    constexpr int width = 30;
    const int filled = static_cast<int>(fraction * width);
    text << '\r' << m_label << " [" << std::string(filled, '#') << std::string(width - filled, '-') << ']'
         << tail;
    if (final) text << '\n';
  } else {
    const std::size_t tenth = static_cast<std::size_t>(fraction * 10.0);
    if (!final && tenth <= m_last_tenth) return;
    if (final && m_last_tenth >= 10) return;
    m_last_tenth = final ? 10 : tenth;
    text << m_label << tail << '\n';
  }
  std::lock_guard<std::mutex> print_lock(m_reporter.m_mutex);
  (*m_reporter.m_stream) << text.str() << std::flush;
  m_reporter.m_bar_on_line = m_reporter.m_style == ProgressStyle::bar && !final;
}

} // namespace phantasm
