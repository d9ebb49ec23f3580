// Reporter, the record of what each stage modelled or skipped (screen and run log), and
// ProgressBar, the progress of one long stage, which several threads may advance at once.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace phantasm {

/// How a Reporter shows progress on its stream.
enum class ProgressStyle {
  bar,   ///< a bar redrawn in place (stderr is a terminal)
  lines, ///< a plain line at most every few seconds, and one at the end (stderr is a file or a pipe)
  none,  ///< nothing (--quiet)
};

class Reporter;

/// Told of a long stage's progress: its label ("anatomy", "deform", "voxelize", "mri",
/// "writing"), the fraction done (0..1) and what is being done now. Called from whichever thread
/// advances the stage, at most every 100 ms per stage and once when the stage ends. It must not
/// throw: an exception from it requests cancellation (the stage stops at its next poll).
using ProgressCallback =
    std::function<void(const std::string& stage, double fraction, const std::string& detail)>;

/// Progress of one long stage: done/total, elapsed time, an estimate of the time left, and a
/// detail of what is being done (progress_detail()). advance() may be called from several
/// threads at once. While it lives, a ticker redraws it every second (a bar) or writes a line
/// every few seconds (plain lines), so a step that cannot report (CGAL's mesher) still shows
/// that it runs and for how long.
class ProgressBar {
public:
  ProgressBar(Reporter& reporter, std::string label, std::size_t total);
  /// A bar that progress_detail() does not reach: for work run on a thread of its own beside a
  /// stage whose bar is on screen (bars of one thread nest; bars of two threads would not).
  struct Unlisted {};
  ProgressBar(Reporter& reporter, std::string label, std::size_t total, Unlisted);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// Marks `steps` more units of work as done.
  void advance(std::size_t steps = 1);
  /// Marks all work as done and ends the bar's line (also done by the destructor, which during
  /// an exception, such as a cancellation, ends the line where the work stopped instead).
  void finish();
  /// What is being done now, shown after the counts ("ball: tet meshing", "frame 2/5,
  /// iteration 40, residual 3.1e-04"); empty clears it.
  void set_detail(std::string detail);

private:
  void draw(std::size_t done, bool final, bool tick = false);
  /// Tells the reporter's progress callback, if any (throttled unless final).
  void notify(std::size_t done, bool final);
  void start_ticker();
  void stop_ticker();

  Reporter& m_reporter;
  std::string m_label;
  std::size_t m_total;
  std::atomic<std::size_t> m_done{0};
  std::string m_detail;
  std::chrono::steady_clock::time_point m_start;
  std::chrono::steady_clock::time_point m_last_draw;
  std::atomic<std::int64_t> m_last_notify_ns{0}; ///< when the progress callback was last called
  bool m_finished = false;
  bool m_stop_ticker = false;
  int m_uncaught_exceptions = 0;
  ProgressBar* m_outer = nullptr; ///< the bar that was innermost before this one
  bool m_listed = true;           ///< progress_detail() may reach it (not Unlisted)
  std::mutex m_mutex;
  std::condition_variable m_wake;
  std::thread m_ticker;
};

/// Sets the detail of the innermost living ProgressBar (none: does nothing), so that code deep
/// inside a stage (a solver's iterations, an organ's fitting phases) can say what it does
/// without being handed the bar. Thread-safe while that bar lives.
void progress_detail(std::string detail);

/// True when a bar lives and its detail was last set 200 ms ago or more: loops call it before
/// formatting a detail, so that a tight loop does not format strings nobody will see.
bool progress_detail_due() noexcept;

/// While one lives, progress_detail() called on its thread does nothing and progress_detail_due()
/// is false there: work run beside a stage (on a thread of its own, its parallel loops on that
/// thread alone) does not write its details onto that stage's bar.
class QuietProgressDetails {
public:
  QuietProgressDetails();
  ~QuietProgressDetails();
  QuietProgressDetails(const QuietProgressDetails&) = delete;
  QuietProgressDetails& operator=(const QuietProgressDetails&) = delete;

private:
  bool m_was_quiet;
};

/// The record of what each stage modelled and what it skipped, shown on stderr (unless quiet)
/// and kept for the run's log file.
class Reporter {
public:
  Reporter(std::ostream& stream, ProgressStyle style);

  /// A reporter that prints nothing and only keeps the log.
  static Reporter silent();

  /// "[stage] message": what was modelled, and why.
  void modelled(const std::string& stage, const std::string& message);
  /// "[stage] skipped: message": what the scene did not need.
  void skipped(const std::string& stage, const std::string& message);
  /// "[stage] warning: message": a result the run could not vouch for (an unconverged solve,
  /// inverted elements); in the log, and on stderr even when quiet.
  void warning(const std::string& stage, const std::string& message);
  /// A note that belongs on screen but not in the log (timings, where files went).
  void note(const std::string& message);
  /// Calls `callback` with the progress of every stage's bar from now on (whatever the style:
  /// the Python module's progress= argument). Set it before the stages run.
  void set_progress_callback(ProgressCallback callback) { m_callback = std::move(callback); }

  /// The log lines so far, in order, without timings (deterministic for a given scene).
  const std::vector<std::string>& log_lines() const { return m_log; }
  ProgressStyle style() const { return m_style; }

private:
  friend class ProgressBar;
  void print(const std::string& line);
  /// Writes one log line; on a terminal, first clears a bar left mid-line. Needs m_mutex held.
  void write_line(const std::string& line);

  std::ostream* m_stream;
  ProgressStyle m_style;
  std::vector<std::string> m_log;
  ProgressCallback m_callback;
  /// A bar is drawn on the current line without its newline yet (bar style), guarded by m_mutex.
  bool m_bar_on_line = false;
  std::mutex m_mutex;
};

/// The style that suits a stream: a bar on a terminal, plain lines otherwise, none when quiet.
ProgressStyle progress_style_for(int file_descriptor, bool quiet);

} // namespace phantasm
