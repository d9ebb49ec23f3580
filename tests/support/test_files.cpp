// The tests' own file helpers: a test program removes the folders of its passed tests.

#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using phantasm::testing::fresh_folder;
using phantasm::testing::run_command;

// Registered only in a program started by the test below (PHANTASM_FILES_CHILD set), so that a
// run of the suite has no test that skips: it makes a folder with a file in it, prints the
// folder's path and passes or fails as asked.
class ChildMakesAFolder : public ::testing::Test {
public:
  void TestBody() override {
    const fs::path folder = fresh_folder("files-child");
    phantasm::testing::write_text_file(folder / "result.txt", "kept\n");
    std::printf("folder %s\n", folder.c_str());
    if (std::string(std::getenv("PHANTASM_FILES_CHILD")) == "fail") ADD_FAILURE() << "failed as asked";
  }
};

const bool child_registered = [] {
  if (std::getenv("PHANTASM_FILES_CHILD") == nullptr) return false;
  ::testing::RegisterTest("TestFoldersChild", "MakesAFolder", nullptr, nullptr, __FILE__, __LINE__,
                          []() -> ::testing::Test* { return new ChildMakesAFolder; });
  return true;
}();

fs::path child_folder(const std::string& outcome, const std::string& keep = "") {
  std::vector<std::string> argv{"/usr/bin/env", "PHANTASM_FILES_CHILD=" + outcome};
  if (!keep.empty())
    argv.push_back("PHANTASM_KEEP_TEST_FOLDERS=" + keep);
  else
    argv.insert(argv.begin() + 1, {"-u", "PHANTASM_KEEP_TEST_FOLDERS"});
  argv.push_back(fs::read_symlink("/proc/self/exe").string());
  argv.push_back("--gtest_filter=TestFoldersChild.MakesAFolder");
  const auto result = run_command(argv);
  EXPECT_EQ(result.exit_code, outcome == "fail" ? 1 : 0) << result.out << result.err;
  std::istringstream lines(result.out);
  std::string line;
  while (std::getline(lines, line))
    if (line.rfind("folder ", 0) == 0) return line.substr(7);
  ADD_FAILURE() << "the child printed no folder:\n" << result.out;
  return {};
}

} // namespace

TEST(TestFolders, APassedProgramRemovesItsFoldersAFailedOneKeepsThem) {
  const fs::path passed = child_folder("pass");
  ASSERT_FALSE(passed.empty());
  EXPECT_FALSE(fs::exists(passed)) << passed << " was left by a program whose tests passed";

  const fs::path failed = child_folder("fail");
  ASSERT_FALSE(failed.empty());
  EXPECT_TRUE(fs::exists(failed / "result.txt")) << failed << " of a failed test was removed";
  fs::remove_all(failed);

  const fs::path kept = child_folder("pass", "1");
  ASSERT_FALSE(kept.empty());
  EXPECT_TRUE(fs::exists(kept / "result.txt"))
      << kept << " was removed though PHANTASM_KEEP_TEST_FOLDERS was set";
  fs::remove_all(kept);
}
