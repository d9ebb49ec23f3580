#pragma once

// `phantasm run` under /usr/bin/time: the peak resident memory and processor time a run took,
// which the cost estimate (pipeline/cost_estimate.hpp) is held to.

#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace phantasm::testing {

struct MeasuredRun {
  double peak_bytes = 0.0;
  double cpu_seconds = 0.0; ///< user + system, all threads
  double wall_seconds = 0.0;
  std::string err; ///< what the run wrote to stderr, /usr/bin/time's line last
};

/// Runs `phantasm run SCENE -o OUT -q [EXTRA...]` under /usr/bin/time, expects exit code 0 and
/// reads what /usr/bin/time measured.
inline MeasuredRun measure_run(const std::filesystem::path& scene, const std::filesystem::path& out,
                               const std::vector<std::string>& extra = {}) {
  // OpenMP threads wait passively: spinning threads on a shared machine add processor time
  // that does no work (a run of two-balls.yaml measured 10.1 s instead of 4.8 s that way).
  std::vector<std::string> argv = {"/usr/bin/env",
                                   "OMP_WAIT_POLICY=passive",
                                   "/usr/bin/time",
                                   "-f",
                                   "phantasm-time %M %U %S %e",
                                   PHANTASM_EXECUTABLE,
                                   "run",
                                   scene.string(),
                                   "-o",
                                   out.string(),
                                   "-q"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  const CommandResult result = run_command(argv);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  MeasuredRun measured;
  measured.err = result.err;
  const std::size_t at = result.err.rfind("phantasm-time ");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no /usr/bin/time line in: " << result.err;
    return measured;
  }
  std::istringstream line(result.err.substr(at + 14));
  double kb = 0.0, user = 0.0, system = 0.0;
  line >> kb >> user >> system >> measured.wall_seconds;
  measured.peak_bytes = kb * 1024.0;
  measured.cpu_seconds = user + system;
  return measured;
}

} // namespace phantasm::testing
