#pragma once

// File helpers shared by tests.

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>

namespace phantasm::testing {

/// A new empty folder under the system's temporary folder, unique to this process and name.
inline std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder =
      std::filesystem::temp_directory_path() / ("phantasm-test-" + name + "-" + std::to_string(::getpid()));
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

inline void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// A dataset's dseg.tsv: label value by organ or tissue name.
inline std::map<std::string, int> dseg_table(const std::filesystem::path& path) {
  std::map<std::string, int> table;
  std::istringstream in(read_file(path));
  std::string line;
  std::getline(in, line); // header
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    int index = 0;
    std::string name;
    if (fields >> index >> name) table[name] = index;
  }
  return table;
}

} // namespace phantasm::testing
