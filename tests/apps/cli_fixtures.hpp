#pragma once

// Shared helpers of the phantasm command tests.

#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace phantasm::testing {

inline const std::filesystem::path k_source_dir = PHANTASM_SOURCE_DIR;
inline const std::string k_phantasm = PHANTASM_EXECUTABLE;
inline const std::filesystem::path k_head_scene = k_source_dir / "data-synthetic" / "head.yaml";
/// Three organs on coarse meshes: command tests that run many times use it.
inline const std::filesystem::path k_small_scene =
    k_source_dir / "tests" / "data" / "scenes" / "small-head.yaml";

/// Words of a library's own messages (the C++ library's, yaml-cpp's, nlohmann's, the runtime's),
/// none of which may reach the user: a message says in the project's words what was expected
/// and what was found.
inline const std::vector<std::string> k_raw_library_markers = {
    "stoul",          "stoi",        "stod",         "stol",
    "bad conversion", "bad_alloc",   "basic_",       "filesystem error",
    "json.exception", "parse_error", "yaml-cpp",     "terminate called",
    "bad file",       "operator[]",  "invalid node", "unknown escape character"};

/// The first library marker a message holds, or "" when it holds none.
inline std::string raw_library_marker(const std::string& message) {
  for (const std::string& marker : k_raw_library_markers)
    if (message.find(marker) != std::string::npos) return marker;
  return {};
}

/// Whether a dataset file holds a run's measured times, which differ from run to run: a subject's
/// timing.json, its report (derivatives/phantasm/sub-<id>.html) and the dataset's page
/// (derivatives/phantasm/index.html, which also differs from shard to shard; docs/report.md).
inline bool holds_run_times(const std::filesystem::path& relative) {
  const std::string name = relative.filename().string();
  return name == "timing.json" ||
         (relative.parent_path().filename() == "phantasm" && relative.extension() == ".html" &&
          (name.rfind("sub-", 0) == 0 || name == "index.html"));
}

/// Every regular file under a folder, by path relative to it, with its bytes; files that hold a
/// run's measured times (holds_run_times) are left out.
inline std::map<std::string, std::string> folder_contents(const std::filesystem::path& folder) {
  std::map<std::string, std::string> contents;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file() && !holds_run_times(std::filesystem::relative(entry.path(), folder))) {
      contents[std::filesystem::relative(entry.path(), folder).generic_string()] = read_file(entry.path());
    }
  }
  return contents;
}

/// The scene `source` with `replace` swapped for `with` (its first occurrence), written to
/// folder/scene.yaml; the calling test fails if the text lacks `replace`.
inline std::filesystem::path scene_variant(const std::filesystem::path& source,
                                           const std::filesystem::path& folder, const std::string& replace,
                                           const std::string& with) {
  std::string text = read_file(source);
  const std::size_t at = text.find(replace);
  EXPECT_NE(at, std::string::npos) << source << " lacks " << replace;
  if (at != std::string::npos) text.replace(at, replace.size(), with);
  std::filesystem::create_directories(folder);
  const std::filesystem::path scene = folder / "scene.yaml";
  write_text_file(scene, text);
  return scene;
}

} // namespace phantasm::testing
