#include "io/dataset_layout.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <fstream>
#include <random>
#include <thread>

using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

struct ReferenceRun {
  std::map<std::string, std::string> files;
  int milliseconds = 0; ///< how long it took (without write delays)
};

/// The files of an uninterrupted run, to compare interrupted runs with.
const ReferenceRun& reference() {
  static const ReferenceRun run = [] {
    const fs::path out = fresh_folder("interrupt-reference") / "out";
    const auto start = std::chrono::steady_clock::now();
    const CommandResult result =
        run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "-q"});
    EXPECT_EQ(result.exit_code, 0) << result.err;
    const auto elapsed = std::chrono::steady_clock::now() - start;
    return ReferenceRun{
        folder_contents(out),
        static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(elapsed).count())};
  }();
  return run;
}

const std::map<std::string, std::string>& reference_run() {
  return reference().files;
}

bool is_temporary(const std::string& relative_path) {
  return fs::path(relative_path).filename().string().find(".phantasm-tmp-") != std::string::npos;
}

/// Starts a slowed-down run, sends a signal after a delay, and checks that every file under a
/// final name is complete, i.e. byte-identical to the uninterrupted run's file. Returns whether
/// the signal arrived before the run ended.
bool interrupt_and_check(int signal_number, int delay_ms, const fs::path& out, bool expect_no_temporaries) {
  // 2 ms per 4 KiB chunk stretches the writes (about 2 MB of meshes) over half a second or more.
  BackgroundProcess run(
      {k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "--force", "--write-delay-ms", "2"});
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  run.send_signal(signal_number);
  const int exit_code = run.wait();
  if (signal_number == SIGINT || signal_number == SIGTERM) {
    // 130 after SIGINT, 143 after SIGTERM: the shell's code for a program the signal ended.
    EXPECT_TRUE(exit_code == 128 + signal_number || exit_code == 0) << exit_code;
  } else {
    EXPECT_TRUE(exit_code == 128 + SIGKILL || exit_code == 0) << exit_code;
  }
  const auto& reference = reference_run();
  const bool interrupted = exit_code != 0;
  if (!fs::exists(out)) return interrupted;
  for (const auto& [path, bytes] : folder_contents(out)) {
    if (is_temporary(path)) {
      EXPECT_FALSE(expect_no_temporaries) << "temporary file left: " << path;
      continue;
    }
    if (reference.count(path) == 0) {
      ADD_FAILURE() << "unexpected file " << path;
      continue;
    }
    EXPECT_EQ(bytes, reference.at(path)) << "partial or wrong file under a final name: " << path;
  }
  return interrupted;
}

void rerun_with_force_completes(const fs::path& out) {
  const CommandResult rerun =
      run_command({k_phantasm, "run", k_small_scene.string(), "-o", out.string(), "--force", "-q"});
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_EQ(folder_contents(out), reference_run()); // complete, and no temporary file left behind
}

/// Interrupts runs at four random moments (seeded), each into its own folder, then reruns the
/// last interrupted one with --force (each rerun is a whole run; one shows that --force completes
/// what a signal left). At least two signals must land while the run is still writing.
void interrupt_at_random_moments(int signal_number, unsigned seed, const std::string& name,
                                 bool expect_no_temporaries) {
  std::mt19937 random(seed);
  // Signals land anywhere from the anatomy stage to the end of the (slowed) writes; the
  // reference run's time scales the range to this build (sanitizers are several times slower).
  std::uniform_int_distribution<int> delay(20, 300 + reference().milliseconds);
  const fs::path root = fresh_folder(name);
  int interrupted = 0;
  fs::path last_interrupted;
  for (int attempt = 0; attempt < 4; ++attempt) {
    SCOPED_TRACE("attempt " + std::to_string(attempt));
    const fs::path out = root / ("out" + std::to_string(attempt));
    if (interrupt_and_check(signal_number, delay(random), out, expect_no_temporaries)) {
      ++interrupted;
      last_interrupted = out;
    }
  }
  EXPECT_GE(interrupted, 2) << "the signal should arrive while the run is writing";
  if (!last_interrupted.empty()) rerun_with_force_completes(last_interrupted);
}

} // namespace

TEST(InterruptedRun, SigintLeavesOnlyCompleteFilesAndNoTemporaries) {
  interrupt_at_random_moments(SIGINT, 20261122, "sigint", true);
}

TEST(InterruptedRun, SigtermLeavesOnlyCompleteFilesAndNoTemporariesAndExits143) {
  interrupt_at_random_moments(SIGTERM, 20261124, "sigterm", true);
}

TEST(InterruptedRun, SigkillLeavesNoPartialFileUnderAFinalName) {
  interrupt_at_random_moments(SIGKILL, 1122, "sigkill", false);
}

TEST(InterruptedRun, ARunKilledRepeatedlyIntoOneFolderStillEndsComplete) {
  const fs::path out = fresh_folder("sigkill-repeated") / "out";
  // Kills at a third, two thirds and all of the reference run's time (writes are slowed, so the
  // last lands while files are being written); at least one must stop the run.
  const int t = reference().milliseconds;
  int interrupted = 0;
  for (int delay_ms : {t / 3, 2 * t / 3, t})
    interrupted += interrupt_and_check(SIGKILL, delay_ms, out, false);
  EXPECT_GE(interrupted, 1);
  rerun_with_force_completes(out);
}

namespace {

struct SignalledRun {
  int exit_code = -1;
  double seconds_after_signal = 0.0;
  std::string err; ///< its standard error (progress lines and messages)
};

/// Starts `argv`, waits until its standard error shows `marker` (a stage's last progress line;
/// empty: at once), then `delay_ms`, sends the signal and waits for the end.
SignalledRun signal_after(const std::vector<std::string>& argv, const fs::path& err_file,
                          const std::string& marker, int delay_ms, int signal_number) {
  BackgroundProcess run(argv, err_file.string());
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!marker.empty() && read_file(err_file).find(marker) == std::string::npos && !run.ended() &&
         std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  const auto sent = std::chrono::steady_clock::now();
  run.send_signal(signal_number);
  SignalledRun result;
  result.exit_code = run.wait();
  result.seconds_after_signal =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
  result.err = read_file(err_file);
  return result;
}

/// What an interrupted run may leave: no temporary, and no completion marker (provenance.json,
/// which batch resumption reads as "this subject is complete").
void expect_no_temporary_and_no_marker(const fs::path& out) {
  if (!fs::exists(out)) return;
  for (const auto& [path, bytes] : folder_contents(out)) {
    EXPECT_FALSE(is_temporary(path)) << "temporary file left: " << path;
    EXPECT_NE(fs::path(path).filename(), "provenance.json") << "a completion marker that lies: " << path;
  }
}

} // namespace

// The large organ's CGAL tet mesh takes minutes; the signal lands inside the mesher (its domain
// oracle polls the flag) at several moments, and the run ends long before the stage would have.
TEST(InterruptedRun, ASignalInsideTheMeshingOfALargeOrganEndsTheRunAtOnce) {
  const fs::path scene = k_source_dir / "tests" / "data" / "scenes" / "large-organ.yaml";
  const fs::path root = fresh_folder("large-organ");
  int attempt = 0;
  for (const auto& [signal_number, delay_ms] :
       std::vector<std::pair<int, int>>{{SIGINT, 1500}, {SIGTERM, 4000}}) {
    SCOPED_TRACE("signal " + std::to_string(signal_number) + " after " + std::to_string(delay_ms) + " ms");
    const fs::path out = root / ("out" + std::to_string(attempt++));
    const SignalledRun run = signal_after({k_phantasm, "run", scene.string(), "-o", out.string()},
                                          root / "err.txt", "", delay_ms, signal_number);
    EXPECT_EQ(run.exit_code, 128 + signal_number) << run.err;
    // Behaviour, not timing: the anatomy stage never ended (it runs for minutes), and the exit
    // came within a generous bound of the signal (sanitizer builds are several times slower).
    EXPECT_EQ(run.err.find("anatomy 100%"), std::string::npos) << run.err;
    EXPECT_LT(run.seconds_after_signal, 30.0) << run.err;
    EXPECT_NE(run.err.find("interrupted"), std::string::npos) << run.err;
    expect_no_temporary_and_no_marker(out);
  }
}

// The small head on a 0.5 mm grid: voxelization takes seconds (3.4 s on 2 idle cores; at 1 mm it
// takes 0.6 s, and a signal 0.9 s after the deformation could land after it). Signals land
// inside it, and the run ends before the stage does.
TEST(InterruptedRun, ASignalInsideVoxelizationEndsTheRunBeforeTheStageEnds) {
  const fs::path root = fresh_folder("voxelization");
  std::string text = read_file(k_small_scene);
  const std::string coarse = "voxel_size_mm: 2.0";
  ASSERT_NE(text.find(coarse), std::string::npos);
  text.replace(text.find(coarse), coarse.size(), "voxel_size_mm: 0.5");
  const fs::path scene = root / "fine-grid.yaml";
  std::ofstream(scene) << text;
  int attempt = 0;
  for (const auto& [signal_number, delay_ms] :
       std::vector<std::pair<int, int>>{{SIGINT, 50}, {SIGTERM, 400}, {SIGINT, 900}}) {
    SCOPED_TRACE("signal " + std::to_string(signal_number) + " " + std::to_string(delay_ms) +
                 " ms after the deformation stage ended");
    const fs::path out = root / ("out" + std::to_string(attempt++));
    const SignalledRun run = signal_after({k_phantasm, "run", scene.string(), "-o", out.string()},
                                          root / "err.txt", "deform 100%", delay_ms, signal_number);
    ASSERT_NE(run.err.find("deform 100%"), std::string::npos) << run.err;
    EXPECT_EQ(run.exit_code, 128 + signal_number) << run.err;
    EXPECT_EQ(run.err.find("voxelize 100%"), std::string::npos) << "the stage ran to its end\n" << run.err;
    expect_no_temporary_and_no_marker(out);
  }
}

namespace {

/// A dataset of one subject (sub-01) whose provenance lists one file, a large reference label
/// map (128 x 128 x 256 uint8: 4 MiB, four pieces of a read), for the commands that read datasets.
fs::path large_label_dataset(const fs::path& root) {
  const fs::path dataset = root / "dataset";
  const phantasm::DatasetLayout layout(dataset, "01");
  phantasm::ImageGrid grid;
  grid.dims = {128, 128, 256};
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()));
  for (std::size_t i = 0; i < labels.size(); ++i)
    labels[i] = static_cast<std::int32_t>(i / 4096 % 7);
  const fs::path dseg = layout.dseg(phantasm::PhantomState::reference);
  phantasm::write_nifti_labels(dseg, grid, labels);
  const nlohmann::json provenance = {{"files", {dseg.lexically_relative(dataset).generic_string()}}};
  write_text_file(layout.provenance(), provenance.dump());
  return dataset;
}

/// Polls (every 5 ms, for at most a minute, while the process runs) until `done` holds.
template <class Condition>
void wait_until(BackgroundProcess& process, Condition done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  while (!process.ended() && std::chrono::steady_clock::now() < give_up && !done())
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

} // namespace

// An HDF5 export writes each array in blocks of chunks and polls between them: a signal while a
// large array is written ends the export at once with 130, removes the temporary file, and the
// file already under the final name (an earlier export) stays as it was.
TEST(InterruptedExport, ASignalWhileAnArrayIsWrittenKeepsTheEarlierFileAndLeavesNoTemporary) {
  const fs::path root = fresh_folder("interrupted-hdf5");
  const fs::path dataset = large_label_dataset(root);
  const std::string dseg =
      phantasm::DatasetLayout(dataset, "01").dseg(phantasm::PhantomState::reference).string();
  const fs::path out = root / "export";
  fs::create_directories(out);
  write_text_file(out / "dataset.h5", "an earlier export");
  // The read: 4 pieces, 100 ms before each. The write: 64 blocks of 16 x 16 x 256 voxels, 50 ms
  // before each (3.2 s).
  BackgroundProcess hdf5({k_phantasm, "hdf5", dataset.string(), "-o", (out / "dataset.h5").string(),
                          "--chunk", "16", "--read-delay-ms", "100", "--write-delay-ms", "50"},
                         (root / "err.txt").string());
  // The label map is read (open), then closed for good (open again within 50 ms: still reading).
  wait_until(hdf5, [&] { return hdf5.has_open(dseg); });
  wait_until(hdf5, [&] {
    if (hdf5.has_open(dseg)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return !hdf5.has_open(dseg);
  });
  hdf5.send_signal(SIGINT);
  EXPECT_EQ(hdf5.wait(), 130) << read_file(root / "err.txt");
  // The subject was never exported (its progress line comes after its last array).
  EXPECT_EQ(read_file(root / "err.txt").find("[hdf5] sub-01"), std::string::npos)
      << read_file(root / "err.txt");
  EXPECT_EQ(folder_contents(out), (std::map<std::string, std::string>{{"dataset.h5", "an earlier export"}}));
}

// `eval` reads its volumes in pieces and polls between them: a signal while a large label map is
// read ends it with 143 (SIGTERM) before anything else is read or written; the --json file
// already there stays as it was. (Unstopped, it would go on to the deformed session's missing
// labels and fail with 2.)
TEST(InterruptedEval, ASignalWhileALargeVolumeIsReadEndsTheEvaluation) {
  const fs::path root = fresh_folder("interrupted-eval");
  const fs::path dataset = large_label_dataset(root);
  const std::string dseg =
      phantasm::DatasetLayout(dataset, "01").dseg(phantasm::PhantomState::reference).string();
  const fs::path json = root / "result" / "evaluation.json";
  fs::create_directories(json.parent_path());
  write_text_file(json, "{}\n");
  // Four pieces, 500 ms before each: 2 s of reading.
  BackgroundProcess eval({k_phantasm, "eval", dataset.string(), "--identity", "--subject", "01", "--json",
                          json.string(), "--read-delay-ms", "500"},
                         (root / "err.txt").string());
  wait_until(eval, [&] { return eval.has_open(dseg); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300)); // past the header, into the voxels
  eval.send_signal(SIGTERM);
  EXPECT_EQ(eval.wait(), 143) << read_file(root / "err.txt");
  EXPECT_NE(read_file(root / "err.txt").find("interrupted"), std::string::npos)
      << read_file(root / "err.txt");
  EXPECT_EQ(folder_contents(json.parent_path()),
            (std::map<std::string, std::string>{{"evaluation.json", "{}\n"}}));
}
