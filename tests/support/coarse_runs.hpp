#pragma once

// One measured run of a shipped scene's coarse copy (coarse_scenes.hpp) for the tests that read
// it: the shipped scenes test checks its dataset (tests/apps/test_shipped_scenes.cpp), the cost
// estimate's test its peak memory (tests/apps/test_cost_estimate.cpp). Each of them ran the same
// copy itself before, the cloth's taking about 26 s twice.

#include "tests/support/coarse_scenes.hpp"
#include "tests/support/files.hpp"
#include "tests/support/measured_run.hpp"
#include "tests/support/shared_output.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <string>
#include <vector>

namespace phantasm::testing {

struct CoarseRun {
  std::filesystem::path scene; ///< the coarse copy
  std::filesystem::path out;   ///< its dataset
  MeasuredRun measured;        ///< what the run took (measure_run)
};

/// The coarse copy of `scene` run by measure_run once for this build of the program and these
/// bytes of the scene and of the headers that make and run the copy (shared_output.hpp), by
/// whichever test needs it first; later tests, in any process, read the same dataset and figures. A run that
/// failed is reported by the test that made it (measure_run's expectations) and made again by the next.
inline CoarseRun shared_coarse_run(const std::filesystem::path& scene) {
  namespace fs = std::filesystem;
  const fs::path support = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "support";
  const std::vector<fs::path> inputs = {scene, support / "coarse_scenes.hpp", support / "measured_run.hpp",
                                        support / "coarse_runs.hpp"};
  const fs::path folder =
      shared_output("coarse-run-" + scene.stem().string(), inputs, [&](const fs::path& into) {
        const MeasuredRun measured = measure_run(coarse_copy(scene, into), into / "out");
        std::ofstream(into / "measured.txt") << std::setprecision(17) << measured.peak_bytes << ' '
                                             << measured.cpu_seconds << ' ' << measured.wall_seconds << '\n';
        std::ofstream(into / "stderr.txt") << measured.err;
        return !::testing::Test::HasFailure();
      });
  CoarseRun run{folder / scene.filename(), folder / "out", {}};
  std::ifstream figures(folder / "measured.txt");
  figures >> run.measured.peak_bytes >> run.measured.cpu_seconds >> run.measured.wall_seconds;
  run.measured.err = read_file(folder / "stderr.txt");
  return run;
}

} // namespace phantasm::testing
