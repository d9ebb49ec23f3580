#pragma once

// Measured runs of coarse scenes (coarse_scenes.hpp) made once and read by every test that checks
// them: a shipped scene's coarse copy for the shipped scenes test (its dataset,
// tests/apps/test_shipped_scenes.cpp) and the cost estimate's test (its peak memory,
// tests/apps/test_cost_estimate.cpp); the coarse Colin head for its own test, the task baselines
// and the registration study. Each of these tests ran the same scene itself before, the cloth's
// taking about 26 s twice, the Colin head's anatomy and deformation about 45 s and 20 s of
// processor time three times.

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
  std::filesystem::path scene; ///< the scene that ran
  std::filesystem::path out;   ///< its dataset
  std::filesystem::path cache; ///< the run's anatomy cache, when it had one
  MeasuredRun measured;        ///< what the run took (measure_run)
};

/// Writes what a run measured, and its stderr, into the folder of its dataset.
inline void write_measured(const std::filesystem::path& folder, const MeasuredRun& measured) {
  std::ofstream(folder / "measured.txt") << std::setprecision(17) << measured.peak_bytes << ' '
                                         << measured.cpu_seconds << ' ' << measured.wall_seconds << '\n';
  std::ofstream(folder / "stderr.txt") << measured.err;
}

/// The run in `folder` of `scene`: its dataset out, its cache, what write_measured wrote.
inline CoarseRun read_coarse_run(const std::filesystem::path& folder, const std::filesystem::path& scene) {
  CoarseRun run{scene, folder / "out", folder / "cache", {}};
  std::ifstream figures(folder / "measured.txt");
  figures >> run.measured.peak_bytes >> run.measured.cpu_seconds >> run.measured.wall_seconds;
  run.measured.err = read_file(folder / "stderr.txt");
  return run;
}

/// The bytes a coarse run depends on besides the program: `scene` and the headers that make and
/// run it.
inline std::vector<std::filesystem::path> coarse_run_inputs(const std::filesystem::path& scene) {
  const std::filesystem::path support = std::filesystem::path(PHANTASM_SOURCE_DIR) / "tests" / "support";
  return {scene, support / "coarse_scenes.hpp", support / "measured_run.hpp", support / "coarse_runs.hpp"};
}

/// The coarse copy of `scene` run by measure_run once for this build of the program and
/// coarse_run_inputs (shared_output.hpp), by whichever test needs it first; later tests, in any
/// process, read the same dataset and figures. A run that failed is reported by the test that
/// made it (measure_run's expectations) and made again by the next.
inline CoarseRun shared_coarse_run(const std::filesystem::path& scene) {
  namespace fs = std::filesystem;
  const fs::path folder = shared_output(
      "coarse-run-" + scene.stem().string(), coarse_run_inputs(scene), [&](const fs::path& into) {
        write_measured(into, measure_run(coarse_copy(scene, into), into / "out"));
        return !::testing::Test::HasFailure();
      });
  return read_coarse_run(folder, folder / scene.filename());
}

/// The coarse Colin head (coarse_colin_head_text) run by measure_run once, as shared_coarse_run,
/// with an anatomy cache of its own that the run fills: it builds the anatomy, so that its
/// measured memory and time are a whole run's, and a test that reads the cache reads an anatomy of
/// this build of the program.
inline CoarseRun shared_coarse_colin_run() {
  namespace fs = std::filesystem;
  const fs::path colin = fs::path(PHANTASM_SOURCE_DIR) / "data-synthetic" / "colin-head.yaml";
  const fs::path folder =
      shared_output("coarse-colin-run", coarse_run_inputs(colin), [](const fs::path& into) {
        write_text_file(into / "colin-coarse.yaml", coarse_colin_head_text());
        write_measured(into, measure_run(into / "colin-coarse.yaml", into / "out",
                                         {"--cache", (into / "cache").string()}));
        return !::testing::Test::HasFailure();
      });
  return read_coarse_run(folder, folder / "colin-coarse.yaml");
}

} // namespace phantasm::testing
