#include "core/abandonable_work.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <sstream>
#include <thread>

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

// A signal at the worst moment of a commit: after the last byte, while the rename is pending
// (the test delay pauses there). The rename of a complete file goes ahead or the old file stays;
// no name ever holds part of a file, no temporary is left, and the next write is refused.
TEST(AtomicFile, ACancellationDuringTheRenameLeavesTheOldOrTheNewFileWhole) {
  const fs::path folder = fresh_folder("cancel-rename");
  const std::string old_bytes = "complete old content", new_bytes(100000, 'n');
  write_file_atomically(folder / "f.txt", old_bytes);
  {
    // Just before the rename: the commit refuses, the old file stays.
    AtomicFileWriter writer(folder / "f.txt");
    writer.write(new_bytes);
    request_cancellation(SIGINT);
    EXPECT_THROW(writer.commit(), Cancelled);
  }
  EXPECT_EQ(read_file(folder / "f.txt"), old_bytes);
  EXPECT_EQ(file_count(folder), 1u);
  reset_cancellation();
  std::thread stop;
  {
    AtomicFileWriter writer(folder / "f.txt");
    writer.write(new_bytes);
    // The commit then pauses 300 ms between closing the temporary file and renaming it.
    set_write_delay_for_testing(300);
    stop = std::thread([] {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      request_cancellation(SIGINT);
    });
    try {
      writer.commit();
    } catch (const Cancelled&) {
    }
  }
  stop.join();
  set_write_delay_for_testing(0);
  const std::string found = read_file(folder / "f.txt");
  EXPECT_TRUE(found == old_bytes || found == new_bytes) << found.size() << " bytes";
  EXPECT_EQ(file_count(folder), 1u); // no temporary
  EXPECT_THROW(write_file_atomically(folder / "f.txt", "more"), Cancelled);
  EXPECT_EQ(read_file(folder / "f.txt"), found);
  EXPECT_EQ(file_count(folder), 1u);
  reset_cancellation();
}

// A process inside work that polls nothing (VTK encoding a mesh, OpenVDB compressing its grids)
// while other threads write files: the watchdog ends it 0.5 s after the signal, and removes the
// temporaries being written first, so that only complete files are left under final names.
TEST(AtomicFile, AnAbandonedProcessRemovesTheTemporariesItWasWriting) {
  const fs::path folder = fresh_folder("abandoned");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    install_cancellation_handlers(true);
    write_file_atomically(folder / "done.txt", "complete");
    AtomicFileWriter open_writer(folder / "open.txt"); // never committed
    open_writer.write("half");
    std::thread polls_nothing([] {
      const AbandonableWork encoding;
      std::this_thread::sleep_for(std::chrono::seconds(60));
    });
    polls_nothing.join();
    ::_exit(0); // reached only if the watchdog did not end the process
  }
  // Wait until the child has made its files, then signal it.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (file_count(folder) < 2 && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(file_count(folder), 2u);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const auto sent = std::chrono::steady_clock::now();
  ASSERT_EQ(::kill(child, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT);
  // Behaviour, not timing: it ended long before its 60 s of work.
  EXPECT_LT(seconds, 30.0);
  EXPECT_EQ(read_file(folder / "done.txt"), "complete");
  EXPECT_EQ(file_count(folder), 1u) << "a temporary was left";
}

TEST(AtomicFile, ARenamedTemporaryIsForgottenAndAFailedRenameKeepsItRegistered) {
  const fs::path folder = fresh_folder("registered");
  {
    std::ofstream(folder / "t") << "x";
    RegisteredTemporary registration(folder / "t");
    EXPECT_NE(registration.rename_to(folder / "missing-folder" / "f"), 0);
    EXPECT_TRUE(fs::exists(folder / "t"));
    EXPECT_EQ(registration.rename_to(folder / "f"), 0);
  }
  EXPECT_EQ(read_file(folder / "f"), "x");
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
  // The same ended pid on this machine by name, and on another machine sharing the folder (a
  // cluster's file system): this machine cannot see the other's processes, so that file stays.
  char host[256] = {};
  ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
  std::string this_host(host);
  for (char& c : this_host) {
    if (c == '/' || c == '-' || static_cast<unsigned char>(c) < 0x21) c = '_';
  }
  std::ofstream(folder / "sub" / (".z.nii.gz.phantasm-tmp-" + std::to_string(ended) + "-3-" + this_host))
      << "x";
  const std::string other = ".w.nii.gz.phantasm-tmp-" + std::to_string(ended) + "-4-node-b." + this_host;
  std::ofstream(folder / "sub" / other) << "being written elsewhere";
  EXPECT_EQ(remove_stale_temporaries(folder), 2u);
  EXPECT_TRUE(fs::exists(folder / "sub" / other));
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
