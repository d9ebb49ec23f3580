#pragma once

// Shared helpers of the phantasm command tests.

#include "tests/support/files.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>

namespace phantasm::testing {

inline const std::filesystem::path k_source_dir = PHANTASM_SOURCE_DIR;
inline const std::string k_phantasm = PHANTASM_EXECUTABLE;
inline const std::filesystem::path k_head_scene = k_source_dir / "data-synthetic" / "head.yaml";
/// Three organs on coarse meshes: command tests that run many times use it.
inline const std::filesystem::path k_small_scene =
    k_source_dir / "tests" / "data" / "scenes" / "small-head.yaml";

/// Every regular file under a folder, by path relative to it, with its bytes.
inline std::map<std::string, std::string> folder_contents(const std::filesystem::path& folder) {
  std::map<std::string, std::string> contents;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) {
      contents[std::filesystem::relative(entry.path(), folder).generic_string()] = read_file(entry.path());
    }
  }
  return contents;
}

} // namespace phantasm::testing
