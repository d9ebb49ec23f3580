#pragma once

// Shared helpers of the phantasm command tests.

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

/// A new empty folder under the system's temporary folder, unique to this process and name.
inline std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder =
      std::filesystem::temp_directory_path() / ("phantasm-cli-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

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
