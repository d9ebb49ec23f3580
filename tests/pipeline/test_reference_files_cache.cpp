// The reference session's files kept across runs (pipeline/reference_files_cache.hpp): the first
// write stores the file's bytes, later ones copy them without making the file, other keys and
// roles do not share, and damaged bytes are not copied.

#include "core/progress.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/reference_files_cache.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// The entries of a cache folder that hold files.
std::vector<fs::path> file_entries(const fs::path& cache) {
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(cache))
    if (entry.path().filename().string().rfind("file-", 0) == 0) entries.push_back(entry.path());
  return entries;
}

} // namespace

TEST(ReferenceFilesCache, TheFirstWriteStoresTheBytesAndLaterOnesCopyThem) {
  const fs::path folder = fresh_folder("reference-files-cache");
  const fs::path cache = folder / "cache";
  fs::create_directories(cache);
  Reporter quiet = Reporter::silent();
  int made = 0;
  std::string content = std::string(100000, 'x') + "the file";
  const FileWriter write = [&](const fs::path& path) {
    ++made;
    write_file_atomically(path, content);
  };
  const std::string key(64, 'a');
  write_through_cache(cache, key, "ses-ref_T1w.nii.gz", write, quiet)(folder / "a.nii.gz");
  EXPECT_EQ(made, 1);
  ASSERT_EQ(file_entries(cache).size(), 1u);
  const std::string first = content;
  content = "other bytes"; // a copy does not call the writer
  write_through_cache(cache, key, "ses-ref_T1w.nii.gz", write, quiet)(folder / "b.nii.gz");
  EXPECT_EQ(made, 1);
  EXPECT_TRUE(read_file(folder / "b.nii.gz") == first);

  // Another key or role: made and stored apart.
  write_through_cache(cache, std::string(64, 'b'), "ses-ref_T1w.nii.gz", write, quiet)(folder / "c.nii.gz");
  write_through_cache(cache, key, "ses-ref_T2w.nii.gz", write, quiet)(folder / "d.nii.gz");
  EXPECT_EQ(made, 3);
  EXPECT_EQ(file_entries(cache).size(), 3u);
  EXPECT_EQ(read_file(folder / "d.nii.gz"), "other bytes");

  // No folder or no key: the writer alone, nothing stored.
  write_through_cache({}, key, "ses-ref_T1w.nii.gz", write, quiet)(folder / "e.nii.gz");
  write_through_cache(cache, "", "ses-ref_T1w.nii.gz", write, quiet)(folder / "f.nii.gz");
  EXPECT_EQ(made, 5);
  EXPECT_EQ(file_entries(cache).size(), 3u);

  // Cut short or a flipped byte: not copied; made again with a warning, and stored anew.
  content = first;
  fs::path entry;
  for (const fs::path& candidate : file_entries(cache))
    if (read_file(candidate).find("the file") != std::string::npos) entry = candidate;
  ASSERT_FALSE(entry.empty());
  const std::string stored = read_file(entry);
  std::string flipped = stored;
  flipped[stored.size() / 2] ^= 1;
  for (const std::string& damaged : {stored.substr(0, stored.size() - 10), flipped}) {
    write_text_file(entry, damaged);
    const int before = made;
    write_through_cache(cache, key, "ses-ref_T1w.nii.gz", write, quiet)(folder / "g.nii.gz");
    EXPECT_EQ(made, before + 1);
    EXPECT_TRUE(read_file(folder / "g.nii.gz") == first);
    EXPECT_TRUE(read_file(entry) == stored);
    EXPECT_TRUE(contains(quiet.log_lines(), "a damaged reference file cache entry"));
  }
}
