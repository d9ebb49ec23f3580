#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

using namespace phantasm;
namespace fs = std::filesystem;

namespace {

fs::path fresh_folder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("phantasm-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

std::string read(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

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
  EXPECT_EQ(read(folder / "a" / "b.json"), "{}\n");
  EXPECT_EQ(file_count(folder), 2u); // the folder a and the file
}

TEST(AtomicFile, TheFinalNameKeepsItsOldContentUntilCommit) {
  const fs::path folder = fresh_folder("replace");
  write_file_atomically(folder / "f.txt", "old");
  {
    AtomicFileWriter writer(folder / "f.txt");
    writer.write("new content");
    EXPECT_EQ(read(folder / "f.txt"), "old");
    EXPECT_TRUE(is_temporary_file_name(writer.temporary_path()));
    EXPECT_EQ(writer.temporary_path().parent_path(), folder);
    writer.commit();
  }
  EXPECT_EQ(read(folder / "f.txt"), "new content");
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
  EXPECT_EQ(read(folder / "f.txt"), "complete");
  EXPECT_EQ(file_count(folder), 1u);
}

TEST(AtomicFile, StaleTemporariesOfAKilledRunAreFoundAndRemoved) {
  const fs::path folder = fresh_folder("stale");
  fs::create_directories(folder / "sub");
  std::ofstream(folder / "sub" / ".x.nii.gz.phantasm-tmp-123-0") << "partial";
  std::ofstream(folder / "sub" / "keep.json") << "{}";
  std::ofstream(folder / ".hidden") << "not ours";
  EXPECT_EQ(remove_stale_temporaries(folder), 1u);
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
