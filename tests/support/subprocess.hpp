#pragma once

// Running the phantasm command from tests, as a user would.

#include <string>
#include <vector>

namespace phantasm::testing {

struct CommandResult {
  int exit_code = -1; ///< the exit status, or 128 + signal number when killed by a signal
  std::string out;    ///< standard output
  std::string err;    ///< standard error
};

/// Runs a program with arguments (no shell), waits for it, and captures both output streams.
CommandResult run_command(const std::vector<std::string>& argv);

/// A program started in the background; its output goes to files.
class BackgroundProcess {
public:
  /// @param stderr_path where its standard error goes (a file the test can read as it grows)
  explicit BackgroundProcess(const std::vector<std::string>& argv,
                             const std::string& stderr_path = "/dev/null");
  ~BackgroundProcess();
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  void send_signal(int signal_number);
  /// Waits for the program to end; returns the exit status, or 128 + signal number.
  int wait();
  /// Whether the program has ended (without waiting).
  bool ended();
  /// Whether the program has `path` open now (a file it reads or writes; Linux's /proc).
  bool has_open(const std::string& path) const;
  /// The process ids of the program's children now (Linux's /proc).
  std::vector<int> children() const;

private:
  int m_pid = -1;
  bool m_waited = false;
  int m_status = 0;
};

} // namespace phantasm::testing
