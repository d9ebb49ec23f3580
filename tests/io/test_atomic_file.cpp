#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

using namespace phantasm;
using phantasm::testing::fresh_folder;
using phantasm::testing::read_file;
namespace fs = std::filesystem;

namespace {

std::size_t file_count(const fs::path& folder) {
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& entry : fs::recursive_directory_iterator(folder))
    ++count;
  return count;
}

} // namespace

TEST(AtomicFile, CommitMakesTheFileAppearWithNoTemporaryLeft) {
  const fs::path folder = fresh_folder("commit");
  write_file_atomically(folder / "a" / "b.json", "{}\n");
  EXPECT_EQ(read_file(folder / "a" / "b.json"), "{}\n");
  EXPECT_EQ(file_count(folder), 2u); // the folder a and the file
}

TEST(AtomicFile, TheFinalNameKeepsItsOldContentUntilCommit) {
  const fs::path folder = fresh_folder("replace");
  write_file_atomically(folder / "f.txt", "old");
  {
    AtomicFileWriter writer(folder / "f.txt");
    writer.write("new content");
    EXPECT_EQ(read_file(folder / "f.txt"), "old");
    EXPECT_TRUE(is_temporary_file_name(writer.temporary_path()));
    EXPECT_EQ(writer.temporary_path().parent_path(), folder);
    writer.commit();
  }
  EXPECT_EQ(read_file(folder / "f.txt"), "new content");
  EXPECT_EQ(file_count(folder), 1u);
}

TEST(AtomicFile, AWriterAbandonedWithoutCommitLeavesNothing) {
  const fs::path folder = fresh_folder("abandon");
  {
    AtomicFileWriter writer(folder / "f.txt");
    writer.write("partial");
  }
  EXPECT_EQ(file_count(folder), 0u);
}

TEST(AtomicFile, CancellationStopsAWriteAndRemovesTheTemporaryFile) {
  const fs::path folder = fresh_folder("cancel");
  write_file_atomically(folder / "f.txt", "complete");
  request_cancellation();
  EXPECT_THROW(write_file_atomically(folder / "f.txt", std::string(1 << 22, 'x')), Cancelled);
  reset_cancellation();
  EXPECT_EQ(read_file(folder / "f.txt"), "complete");
  EXPECT_EQ(file_count(folder), 1u);
}

TEST(AtomicFile, StaleTemporariesOfAKilledRunAreFoundAndRemoved) {
  const fs::path folder = fresh_folder("stale");
  fs::create_directories(folder / "sub");
  // A process that has ended: its temporary file is stale.
  const pid_t ended = ::fork();
  if (ended == 0) ::_exit(0);
  ASSERT_GT(ended, 0);
  ::waitpid(ended, nullptr, 0);
  std::ofstream(folder / "sub" / (".x.nii.gz.phantasm-tmp-" + std::to_string(ended) + "-0")) << "partial";
  // A running process (this one) may still be writing: its temporary file stays.
  const std::string live = ".y.json.phantasm-tmp-" + std::to_string(::getpid()) + "-7";
  std::ofstream(folder / "sub" / live) << "being written";
  std::ofstream(folder / "sub" / "keep.json") << "{}";
  std::ofstream(folder / ".hidden") << "not ours";
  EXPECT_EQ(remove_stale_temporaries(folder), 1u);
  EXPECT_TRUE(fs::exists(folder / "sub" / live));
  EXPECT_TRUE(fs::exists(folder / "sub" / "keep.json"));
  EXPECT_TRUE(fs::exists(folder / ".hidden"));
}

TEST(AtomicFile, UnwritableLocationsRaiseAnErrorNamingThePath) {
  const fs::path folder = fresh_folder("unwritable");
  std::ofstream(folder / "file") << "x";
  try {
    write_file_atomically(folder / "file" / "inside.json", "{}");
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("file"), std::string::npos);
  }
}
