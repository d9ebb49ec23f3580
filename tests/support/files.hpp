#pragma once

// File helpers shared by tests.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

namespace phantasm::testing {

namespace detail {

/// The folders fresh_folder made in this process.
struct MadeFolders {
  std::mutex mutex;
  std::vector<std::filesystem::path> folders;
};

inline MadeFolders& made_folders() {
  static MadeFolders made;
  return made;
}

/// Removes the folders fresh_folder made when the test program ends with every test passed; a
/// failed test keeps its files to show what went wrong, and so does any test while the variable
/// PHANTASM_KEEP_TEST_FOLDERS is set. A whole run of the suite left about 0.4 GB in the temporary
/// folder before, on every run.
class RemoveFoldersOfPassedTests : public ::testing::EmptyTestEventListener {
public:
  void OnTestProgramEnd(const ::testing::UnitTest& unit_test) override {
    if (!unit_test.Passed() || std::getenv("PHANTASM_KEEP_TEST_FOLDERS") != nullptr) return;
    MadeFolders& made = made_folders();
    const std::lock_guard<std::mutex> lock(made.mutex);
    for (const std::filesystem::path& folder : made.folders) {
      std::error_code ignored; // a folder the test removed itself, or one held open, stays as it is
      std::filesystem::remove_all(folder, ignored);
    }
  }
};

} // namespace detail

/// A new empty folder under the system's temporary folder, unique to this process and name. It
/// is removed when the test program ends if every test passed (detail::RemoveFoldersOfPassedTests).
inline std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder =
      std::filesystem::temp_directory_path() / ("phantasm-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  // The listener is appended once, by the first folder; googletest owns and deletes it.
  static const bool listening = [] {
    ::testing::UnitTest::GetInstance()->listeners().Append(new detail::RemoveFoldersOfPassedTests);
    return true;
  }();
  (void)listening;
  detail::MadeFolders& made = detail::made_folders();
  const std::lock_guard<std::mutex> lock(made.mutex);
  made.folders.push_back(folder);
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
