#pragma once

// Helpers shared by the tests of the caches (anatomy, reference state, reference images).

#include "pipeline/dataset_writer.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::testing {

/// The scene of a file that must load.
inline Scene scene_of(const std::filesystem::path& file) {
  const SceneLoadResult loaded = load_scene(file);
  if (!loaded.scene) throw std::runtime_error(format_diagnostics(loaded.problems));
  return *loaded.scene;
}

/// Whether any of the lines holds the text.
inline bool contains(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& line) { return line.find(text) != std::string::npos; });
}

/// Every file of a run, by its path in the dataset, with its bytes.
inline std::map<std::string, std::string> files_of(const RunSummary& run,
                                                   const std::filesystem::path& folder) {
  std::map<std::string, std::string> files;
  for (const std::filesystem::path& file : run.files)
    files[file.generic_string()] = read_file(folder / file);
  return files;
}

/// A run of the scene into `output` with its caches in `cache` (none when empty): its summary
/// and every file it wrote, with its bytes.
inline std::pair<RunSummary, std::map<std::string, std::string>>
run_with_cache(const Scene& scene, const std::filesystem::path& output, const std::filesystem::path& cache) {
  RunOptions options;
  options.output = output;
  options.anatomy_cache = cache;
  Reporter quiet = Reporter::silent();
  const RunSummary summary = run_scene(scene, options, quiet);
  return {summary, files_of(summary, output)};
}

/// The entries (.bin) of a cache folder whose names start with `prefix`.
inline std::vector<std::filesystem::path> cache_entries(const std::filesystem::path& cache,
                                                        const std::string& prefix) {
  std::vector<std::filesystem::path> entries;
  for (const auto& entry : std::filesystem::directory_iterator(cache))
    if (entry.path().filename().string().rfind(prefix, 0) == 0 && entry.path().extension() == ".bin")
      entries.push_back(entry.path());
  return entries;
}

/// Whether a dataset file is the dataset page's summary of a subject, which names the
/// provenance.json it was made with (report/dataset_page.hpp).
inline bool is_page_summary(const std::string& path) {
  return path.find("page-summary.json") != std::string::npos;
}

/// Whether a dataset file is the run's record (log, provenance and the page summary that names
/// it), not its data.
inline bool is_record(const std::string& path) {
  return path.find("log.txt") != std::string::npos || path.find("provenance.json") != std::string::npos ||
         is_page_summary(path);
}

/// A cache key is a SHA-256 (64 hex digits), the same for the same inputs, and different for
/// each one of `changes` applied to `base` (from the key of every other change too).
template <class Inputs>
void expect_every_change_changes_the_key(const Inputs& base,
                                         const std::vector<std::function<void(Inputs&)>>& changes,
                                         const std::function<std::string(const Inputs&)>& key_of) {
  const std::string base_key = key_of(base);
  ASSERT_EQ(base_key.size(), 64u);
  EXPECT_EQ(key_of(base), base_key);
  std::set<std::string> keys{base_key};
  for (std::size_t c = 0; c < changes.size(); ++c) {
    Inputs changed = base;
    changes[c](changed);
    EXPECT_TRUE(keys.insert(key_of(changed)).second) << "change " << c;
  }
}

} // namespace phantasm::testing
