#pragma once

// Outputs that several tests read and none changes (a batch of a sweep, its pairs), made once per
// build of the program instead of once per test: ctest runs each test in a process of its own, so
// a static in the test file would make them again in every test.

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "tests/support/files.hpp"

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace phantasm::testing {

/// The folder `name` under the temporary folder, made by `make(folder)` once for this build of the
/// phantasm executable and these `inputs` (the name holds the program's size and modification
/// time and a hash of the inputs' bytes: a rebuilt program or an edited input makes its own) and
/// read by every later test, in any process. The first test to need it makes it while it holds an
/// exclusive lock, so that a test running alongside waits and then reads it; a mark written after
/// `make` returned true says that it is complete. A make that failed (false) leaves no mark: its
/// caller fails, and the next test makes the folder again from empty. Callers write nothing into
/// the folder.
inline std::filesystem::path shared_output(const std::string& name,
                                           const std::vector<std::filesystem::path>& inputs,
                                           const std::function<bool(const std::filesystem::path&)>& make) {
  namespace fs = std::filesystem;
  const fs::path program(PHANTASM_EXECUTABLE);
  const auto modified = fs::last_write_time(program).time_since_epoch().count();
  std::string bytes;
  for (const fs::path& input : inputs)
    bytes += input.string() + '\n' + read_file(input);
  const fs::path folder =
      fs::temp_directory_path() /
      ("phantasm-test-shared-" + name + "-" + std::to_string(fs::file_size(program)) + "-" +
       std::to_string(modified) + "-" + std::to_string(std::hash<std::string>{}(bytes)));
  const fs::path mark = folder.string() + ".complete";
  const int lock = ::open((folder.string() + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) throw std::runtime_error("cannot lock " + folder.string());
  if (!fs::exists(mark)) {
    fs::remove_all(folder);
    fs::create_directories(folder);
    if (make(folder)) std::ofstream(mark) << "complete\n";
  }
  ::close(lock); // releases the lock
  return folder;
}

} // namespace phantasm::testing
