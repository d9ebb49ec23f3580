// `phantasm batch` end to end on four small heads: jobs and shards give the same bytes, a
// finished batch skips every subject, and a batch killed with SIGKILL at random moments and
// restarted ends with exactly the dataset of an uninterrupted batch.

#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <random>
#include <set>
#include <thread>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_sweep = k_source_dir / "tests" / "data" / "sweeps" / "small-sweep.yaml";

struct ReferenceBatch {
  fs::path folder;
  std::map<std::string, std::string> files;
  int milliseconds = 0;
  std::string err; ///< what it printed (progress)
};

/// The sweep made once with two jobs.
const ReferenceBatch& reference() {
  static const ReferenceBatch batch = [] {
    ReferenceBatch b;
    b.folder = fresh_folder("batch-reference") / "out";
    const auto start = std::chrono::steady_clock::now();
    const CommandResult run =
        run_command({k_phantasm, "batch", k_sweep.string(), "-o", b.folder.string(), "-j", "2"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    b.milliseconds = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start)
            .count());
    b.files = folder_contents(b.folder);
    b.err = run.err;
    return b;
  }();
  return batch;
}

std::size_t count_ending(const std::map<std::string, std::string>& files, const std::string& suffix) {
  std::size_t n = 0;
  for (const auto& [path, bytes] : files)
    n +=
        path.size() >= suffix.size() && path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
  return n;
}

} // namespace

// One test, so that the reference batch is made once: jobs, shards, a finished batch and a
// killed one all end with the same bytes.
TEST(BatchCommand, JobsShardsRestartsAndKillsEndWithTheSameSubjects) {
  const auto& a = reference();
  EXPECT_EQ(count_ending(a.files, "provenance.json"), 4u);
  EXPECT_EQ(count_ending(a.files, "_ses-def_T1w.nii.gz"), 4u);
  const std::string participants = a.files.at("participants.tsv");
  EXPECT_EQ(std::count(participants.begin(), participants.end(), '\n'), 5);
  EXPECT_EQ(participants.rfind("participant_id\tseed\tdeformation.scale\tacquisition.noise_percent\n", 0),
            0u);

  // Three shards, one after the other, into one folder (as three machines would).
  const fs::path sharded = fresh_folder("batch-shards") / "out";
  for (const char* shard : {"1/3", "2/3", "3/3"}) {
    const CommandResult run =
        run_command({k_phantasm, "batch", k_sweep.string(), "-o", sharded.string(), "--shard", shard, "-q"});
    ASSERT_EQ(run.exit_code, 0) << shard << run.err;
  }
  EXPECT_EQ(folder_contents(sharded), a.files);

  // A finished batch makes nothing again.
  const CommandResult again = run_command({k_phantasm, "batch", k_sweep.string(), "-o", a.folder.string()});
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_NE(again.err.find("0 subjects made, 4 already complete, 0 failed"), std::string::npos) << again.err;
  EXPECT_EQ(folder_contents(a.folder), a.files);

  // Killed with SIGKILL at random moments and restarted: exactly the uninterrupted dataset.
  const fs::path out = fresh_folder("batch-killed") / "out";
  std::mt19937 random(20261122);
  // At most a quarter of the whole batch: three kills leave a quarter still to make, so each
  // restart is killed while it is working.
  std::uniform_int_distribution<int> delay(100, std::max(200, a.milliseconds / 4));
  int killed = 0;
  for (int attempt = 0; attempt < 3; ++attempt) {
    BackgroundProcess batch({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "-j", "2", "-q"});
    std::this_thread::sleep_for(std::chrono::milliseconds(delay(random)));
    batch.send_signal(SIGKILL);
    killed += batch.wait() == 128 + SIGKILL;
  }
  EXPECT_GE(killed, 2);
  const CommandResult finish =
      run_command({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "-j", "2"});
  ASSERT_EQ(finish.exit_code, 0) << finish.err;
  // Every file equals the uninterrupted batch's, and nothing else (no temporary file) is there.
  EXPECT_EQ(folder_contents(out), a.files);

  // Interrupted with SIGINT or SIGTERM at random moments: each exits 128 + signal (or 0 when it
  // had finished), leaves the subjects it made and no temporary, and the next batch makes the rest.
  const fs::path signalled = fresh_folder("batch-signalled") / "out";
  int interrupted = 0;
  for (int attempt = 0; attempt < 4; ++attempt) {
    const int signal_number = attempt % 2 == 0 ? SIGINT : SIGTERM;
    BackgroundProcess batch(
        {k_phantasm, "batch", k_sweep.string(), "-o", signalled.string(), "-j", "2", "-q"});
    std::this_thread::sleep_for(std::chrono::milliseconds(delay(random)));
    batch.send_signal(signal_number);
    const int code = batch.wait();
    EXPECT_TRUE(code == 128 + signal_number || code == 0) << code;
    interrupted += code != 0;
    if (!fs::exists(signalled)) continue;
    for (const auto& [path, bytes] : folder_contents(signalled)) {
      EXPECT_EQ(path.find(".phantasm-tmp-"), std::string::npos) << "temporary file left: " << path;
      // What is there is what the uninterrupted batch made (a subject's files are complete).
      if (a.files.count(path) != 0 && path != "participants.tsv") {
        EXPECT_EQ(bytes, a.files.at(path)) << path;
      }
    }
  }
  EXPECT_GE(interrupted, 2);
  const CommandResult rest =
      run_command({k_phantasm, "batch", k_sweep.string(), "-o", signalled.string(), "-j", "2"});
  ASSERT_EQ(rest.exit_code, 0) << rest.err;
  EXPECT_EQ(folder_contents(signalled), a.files);
}

TEST(BatchCommand, ShowsSubjectsDoneFailedAndLeftWithTheTimeLeft) {
  const std::string& err = reference().err;
  EXPECT_NE(err.find("(1 done, 0 failed, 3 left, about "), std::string::npos) << err;
  EXPECT_NE(err.find("(4 done, 0 failed, 0 left)"), std::string::npos) << err;
}

TEST(BatchCommand, BadSweepsAndShardsAreReportedClearly) {
  const fs::path folder = fresh_folder("batch-bad");
  write_text_file(folder / "sweep.yaml", "phantasm_sweep: 1\nbase_scene: " + k_small_scene.string() +
                                             "\nvary:\n  acquisition.noise_percent: {uniform: [5, 1]}\n");
  CommandResult run =
      run_command({k_phantasm, "batch", (folder / "sweep.yaml").string(), "-o", folder.string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(
      run.err.find(
          "sweep.yaml:4:30: vary.acquisition.noise_percent.uniform: expected low <= high, found [5, 1]"),
      std::string::npos)
      << run.err;
  run = run_command({k_phantasm, "batch", k_sweep.string(), "-o", folder.string(), "--shard", "4/3"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--shard: expected i/N with 1 <= i <= N (e.g. 2/3), found '4/3'"), std::string::npos)
      << run.err;
}

// The Snakemake workflow of docs/batch.md (one job per subject) with Debian's snakemake makes the
// same subjects, byte for byte, as `phantasm batch`.
TEST(BatchCommand, SnakemakeWorkflowMakesTheSameSubjects) {
  const fs::path sweep = k_source_dir / "tests" / "data" / "sweeps" / "three-subjects.yaml";
  const fs::path root = fresh_folder("batch-snakemake");
  const CommandResult batch =
      run_command({k_phantasm, "batch", sweep.string(), "-o", (root / "batch").string(), "-q"});
  ASSERT_EQ(batch.exit_code, 0) << batch.err;
  const CommandResult snakemake =
      run_command({"/usr/bin/snakemake", "-s", (k_source_dir / "scripts" / "Snakefile").string(), "--cores",
                   "2", "--directory", root.string(), "--config", "sweep=" + sweep.string(),
                   "out=" + (root / "snakemake").string(), "phantasm=" + k_phantasm});
  ASSERT_EQ(snakemake.exit_code, 0) << snakemake.out << snakemake.err;
  const auto made = folder_contents(root / "batch");
  EXPECT_EQ(
      std::count_if(made.begin(), made.end(),
                    [](const auto& file) { return file.first.find("provenance.json") != std::string::npos; }),
      3);
  EXPECT_EQ(folder_contents(root / "snakemake"), made);
}

// The HDF5 export of a batch, read by h5py: every image, label map, fraction, parameter map, field,
// exact mask, Jacobian and landmark list equals its file (values, shape, affine), chunked and
// compressed, with its kind, units, frame and axes (tests/apps/check_hdf5.py).
TEST(BatchCommand, Hdf5ExportHoldsEveryImageLabelMapAndField) {
  const fs::path sweep = k_source_dir / "tests" / "data" / "sweeps" / "three-subjects.yaml";
  const fs::path root = fresh_folder("batch-hdf5");
  const CommandResult batch =
      run_command({k_phantasm, "batch", sweep.string(), "-o", (root / "out").string(), "-j", "2", "-q"});
  ASSERT_EQ(batch.exit_code, 0) << batch.err;
  const CommandResult export_run =
      run_command({k_phantasm, "hdf5", (root / "out").string(), "-o", (root / "sweep.h5").string()});
  ASSERT_EQ(export_run.exit_code, 0) << export_run.err;
  EXPECT_NE(export_run.err.find("arrays of 3 subjects"), std::string::npos) << export_run.err;
  const CommandResult check =
      run_command({PHANTASM_PYTHON, (k_source_dir / "tests" / "apps" / "check_hdf5.py").string(),
                   (root / "sweep.h5").string(), (root / "out").string()});
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err;
  EXPECT_NE(check.out.find("checked 90 arrays: displacement_field 6, exact_mask 6, fraction 18, image 12, "
                           "jacobian 6, labels 6, landmarks 12, parameter_map 24"),
            std::string::npos)
      << check.out;
  const CommandResult empty =
      run_command({k_phantasm, "hdf5", root.string(), "-o", (root / "x.h5").string()});
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_FALSE(fs::exists(root / "x.h5"));
}

// Subjects whose solve did not converge are listed in the batch's summary; with --strict they
// fail and are not written (#16).
TEST(BatchCommand, UnconvergedSubjectsAreListedAndStrictFailsThem) {
  const fs::path folder = fresh_folder("batch-unconverged");
  write_text_file(folder / "sweep.yaml",
                  "phantasm_sweep: 1\nname: cut-short\nbase_scene: " + k_small_scene.string() +
                      "\nvary:\n  deformation.solver.max_iterations: [1, 1000]\n");
  CommandResult run = run_command(
      {k_phantasm, "batch", (folder / "sweep.yaml").string(), "-o", (folder / "out").string(), "-q"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("[batch] warning: 1 subjects with a solve that did not converge"), std::string::npos)
      << run.err;
  run = run_command({k_phantasm, "batch", (folder / "sweep.yaml").string(), "-o",
                     (folder / "strict").string(), "-q", "--strict"});
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("--strict"), std::string::npos) << run.err;
  EXPECT_EQ(count_ending(folder_contents(folder / "strict"), "provenance.json"), 1u);
}

// Subjects that differ only in what comes after the anatomy share one anatomy cache entry and one
// reference cache entry: the batch builds the anatomy and voxelizes the reference state once (#17
// item 4), and their datasets are those of runs without the cache.
TEST(BatchCommand, SubjectsWithTheSameAnatomyBuildItOnce) {
  const fs::path folder = fresh_folder("batch-anatomy-cache");
  write_text_file(folder / "sweep.yaml",
                  "phantasm_sweep: 1\nname: noise-only\nbase_scene: " + k_small_scene.string() +
                      "\nvary:\n  acquisition.noise_percent: [1, 2, 3]\n");
  const CommandResult run = run_command(
      {k_phantasm, "batch", (folder / "sweep.yaml").string(), "-o", (folder / "out").string(), "-j", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find(": 1 anatomies, 1 built by this batch"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("; 1 reference states, 1 voxelized by this batch"), std::string::npos) << run.err;
  const auto files = folder_contents(folder / "out");
  // The anatomy, the voxelized reference state and its images at each noise level; beside them
  // the reference session's files (pipeline/reference_files_cache.hpp).
  std::size_t anatomies = 0, states = 0, images = 0, stored_files = 0;
  for (const auto& [path, bytes] : files) {
    const std::string name = fs::path(path).filename().string();
    if (fs::path(path).extension() != ".bin") continue;
    anatomies += name.rfind("anatomy-", 0) == 0;
    states += name.rfind("reference-", 0) == 0;
    images += name.rfind("images-", 0) == 0;
    stored_files += name.rfind("file-", 0) == 0;
  }
  EXPECT_EQ(anatomies, 1u);
  EXPECT_EQ(states, 1u);
  EXPECT_EQ(images, 3u);
  EXPECT_GT(stored_files, 0u);
  // The summary counts the images and the stored files too, and what they hold in all.
  EXPECT_NE(run.err.find("; 3 reference image sets, 3 made by this batch"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("; " + std::to_string(stored_files) + " reference-session files, " +
                         std::to_string(stored_files) + " stored by this batch; "),
            std::string::npos)
      << run.err;
  EXPECT_EQ(count_ending(files, "provenance.json"), 3u);
  // A run of the first subject's scene without the cache writes the same files.
  const fs::path alone = folder / "alone";
  ASSERT_EQ(run_command({k_phantasm, "run",
                         (folder / "out" / "derivatives" / "phantasm" / "sub-01" / "scene.yaml").string(),
                         "-o", alone.string(), "-q"})
                .exit_code,
            0);
  std::size_t compared = 0;
  for (const auto& [path, bytes] : folder_contents(alone)) {
    if (path.find("sub-01") == std::string::npos) continue;
    ++compared;
    const std::string in_batch = files.count(path) ? files.at(path) : std::string();
    if (path.find("log.txt") != std::string::npos || path.find("provenance.json") != std::string::npos) {
      // The batch's subject says where its organs came from; the rest of the record is the same.
      EXPECT_NE(in_batch.find("kept in the anatomy cache as entry"), std::string::npos) << path;
      EXPECT_NE(in_batch.find("kept in the reference cache as entry"), std::string::npos) << path;
      continue;
    }
    if (path.find("page-summary.json") != std::string::npos) {
      // It names the provenance.json it was made with (above: not the same); the rest is.
      nlohmann::json a = nlohmann::json::parse(in_batch), b = nlohmann::json::parse(bytes);
      a.erase("provenance_sha256");
      b.erase("provenance_sha256");
      EXPECT_EQ(a, b) << path;
      continue;
    }
    EXPECT_TRUE(in_batch == bytes) << path;
  }
  EXPECT_GT(compared, 50u);
}

namespace {

/// Whether any file under `folder` has a name for which `matches` is true.
template <class Match>
bool any_file(const fs::path& folder, Match matches) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return false;
  for (auto it = fs::recursive_directory_iterator(folder, error); it != fs::recursive_directory_iterator();
       it.increment(error)) {
    if (error) return false; // a folder renamed or removed under the iterator: look again
    if (matches(it->path().filename().string())) return true;
  }
  return false;
}

/// Polls until `matches` holds for a file under `folder` (or the process ends, or 5 min pass).
template <class Match>
void wait_for_file(const fs::path& folder, BackgroundProcess& process, Match matches) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!process.ended() && std::chrono::steady_clock::now() < give_up && !any_file(folder, matches))
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

bool is_temporary_name(const std::string& name) {
  return name.find(".phantasm-tmp-") != std::string::npos;
}

} // namespace

// Signals at the worst moments of a batch: between two subjects (the instant the first one's
// completion marker appears) and while a shard writes the dataset's participants.tsv. Nothing
// already written is damaged: the subject made before the signal stays complete (the next batch
// skips it and leaves its bytes alone), participants.tsv keeps its bytes, no temporary is left.
TEST(BatchCommand, ASignalBetweenTwoSubjectsOrWhileAShardWritesItsTableDamagesNothing) {
  const fs::path out = fresh_folder("batch-worst-moments") / "out";
  // Shard 1/3 holds two subjects; one at a time, so that the second starts when the first ends.
  BackgroundProcess first(
      {k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "--shard", "1/3", "-j", "1", "-q"});
  wait_for_file(out / "derivatives", first,
                [](const std::string& name) { return name == "provenance.json"; });
  first.send_signal(SIGINT);
  EXPECT_EQ(first.wait(), 130);
  const std::map<std::string, std::string> after_first = folder_contents(out);
  EXPECT_EQ(count_ending(after_first, "provenance.json"), 1u);
  for (const auto& [path, bytes] : after_first)
    EXPECT_FALSE(is_temporary_name(path)) << "temporary file left: " << path;

  // Shard 2/3, its writes slowed: SIGTERM while participants.tsv is written (its temporary file
  // exists). It ends with 143, and the folder is exactly as the first batch left it.
  BackgroundProcess second({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "--shard", "2/3", "-q",
                            "--write-delay-ms", "1000"});
  wait_for_file(out, second, [](const std::string& name) {
    return name.rfind(".participants.tsv.phantasm-tmp-", 0) == 0;
  });
  second.send_signal(SIGTERM);
  EXPECT_EQ(second.wait(), 143);
  EXPECT_EQ(folder_contents(out), after_first);

  // The shard started again counts the subject made before the first signal as complete (and is
  // stopped there: making the other subject would show nothing more); its bytes stay.
  const fs::path err = out.parent_path() / "third.txt";
  BackgroundProcess third({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "--shard", "1/3"},
                          err.string());
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  while (read_file(err).find(" to run, ") == std::string::npos && !third.ended() &&
         std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  third.send_signal(SIGINT);
  EXPECT_EQ(third.wait(), 130);
  EXPECT_NE(read_file(err).find("2 of 4 subjects in shard 1/3, 1 already complete, 1 to run"),
            std::string::npos)
      << read_file(err);
  const std::map<std::string, std::string> finished = folder_contents(out);
  for (const auto& [path, bytes] : after_first) { // a subject's files do not depend on the run
    ASSERT_EQ(finished.count(path), 1u) << path;
    EXPECT_EQ(finished.at(path), bytes) << path;
  }
  for (const auto& [path, bytes] : finished)
    EXPECT_FALSE(is_temporary_name(path)) << "temporary file left: " << path;
}

// A job slot keeps one process for its subjects, one after the other; a process that dies while it
// makes a subject (the kernel's out-of-memory killer, a crash) fails that subject alone: the batch
// starts another process for the rest, and the next batch makes the failed one, with the bytes of
// an uninterrupted batch.
TEST(BatchCommand, AJobSlotKeepsItsProcessAndOneThatDiesFailsItsSubjectAlone) {
  const auto& a = reference();
  const fs::path folder = fresh_folder("batch-worker-killed");
  const fs::path out = folder / "out";
  const std::string err_path = (folder / "batch.err").string();
  std::set<int> workers;
  int killed = -1;
  {
    BackgroundProcess batch({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "-j", "1"}, err_path);
    const auto complete = [&] {
      std::size_t n = 0;
      std::error_code error;
      for (auto it = fs::recursive_directory_iterator(out / "derivatives", error);
           !error && it != fs::recursive_directory_iterator(); it.increment(error))
        n += it->path().filename() == "provenance.json";
      return n;
    };
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    while (!batch.ended() && std::chrono::steady_clock::now() < give_up) {
      for (const int pid : batch.children())
        workers.insert(pid);
      // The first subject is complete: its process, the only one so far, makes the second now.
      if (killed < 0 && complete() == 1 && workers.size() == 1) {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        killed = *workers.begin();
        ::kill(killed, SIGKILL);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    EXPECT_EQ(batch.wait(), 1);
  }
  ASSERT_GT(killed, 0);
  // One process for the first two subjects, one more for the last two: not one per subject.
  EXPECT_EQ(workers.size(), 2u);
  const std::string err = read_file(err_path);
  EXPECT_NE(err.find(" failed (signal 9; "), std::string::npos) << err;
  EXPECT_NE(err.find("3 subjects made, 0 already complete, 1 failed"), std::string::npos) << err;
  const CommandResult rest = run_command({k_phantasm, "batch", k_sweep.string(), "-o", out.string(), "-q"});
  ASSERT_EQ(rest.exit_code, 0) << rest.err;
  EXPECT_EQ(folder_contents(out), a.files);
}
