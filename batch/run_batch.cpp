#include "batch/run_batch.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/output_path.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/run_pipeline.hpp"

#include <nlohmann/json.hpp>
#include <omp.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <new>
#include <thread>

namespace phantasm {
namespace {

/// The child's whole life: run one subject, exit with phantasm's exit codes.
[[noreturn]] void run_subject_and_exit(const Sweep& sweep, const SweepSubject& subject,
                                       const std::filesystem::path& output, int threads, pid_t parent,
                                       bool strict, const std::filesystem::path& anatomy_cache) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL); // a batch killed outright takes its subjects with it
  if (::getppid() != parent) ::_exit(1);
  // SIGINT from the terminal reaches the subject and the batch, which then sends SIGTERM: a
  // subject counts every signal as a request to stop, so it always cleans up before it exits.
  install_cancellation_handlers(false);
  omp_set_num_threads(threads);
  int code = 0;
  try {
    const SceneLoadResult loaded = parse_scene(subject.scene_text, sweep.base_scene);
    if (!loaded.scene) throw InputError(format_diagnostics(loaded.problems));
    Reporter quiet = Reporter::silent();
    RunOptions run_options;
    run_options.output = output;
    run_options.force = true;
    run_options.strict = strict;
    run_options.anatomy_cache = anatomy_cache;
    run_scene(*loaded.scene, run_options, quiet);
  } catch (const Cancelled&) {
    code = 128 + (cancellation_signal() > 0 ? cancellation_signal() : SIGINT);
  } catch (const InputError& error) {
    std::cerr << "sub-" << subject.id << ": " << error.what() << '\n';
    code = 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "sub-" << subject.id
              << ": error: out of memory: expected a subject that fits in this machine's memory with --jobs "
                 "at a time, found more than it holds\n";
    code = 1;
  } catch (const std::filesystem::filesystem_error& error) {
    // A file where the subject's folders go is the user's to move, like any input error.
    if (const std::string message = file_in_the_way_message(error); !message.empty()) {
      std::cerr << "sub-" << subject.id << ": " << message << '\n';
      code = 2;
    } else {
      std::cerr << "sub-" << subject.id << ": error: " << error.path1().string() << ": "
                << error.code().message() << '\n';
      code = 1;
    }
  } catch (const std::exception& error) {
    std::cerr << "sub-" << subject.id << ": error: " << error.what() << '\n';
    code = 1;
  }
  std::cerr.flush();
  ::_exit(code);
}

struct Running {
  std::size_t subject;
  std::chrono::steady_clock::time_point start;
  bool signalled = false; ///< asked to stop once (a second signal would end it before it cleans up)
};

/// "3 done, 1 failed, 6 left, about 2 min 10 s left": the subjects left times the mean time of
/// those made so far, over the jobs that run at once.
std::string batch_status(const BatchSummary& summary, std::size_t to_run, double subject_seconds, int jobs) {
  const std::size_t finished = summary.ran + summary.failed.size();
  const std::size_t left = to_run > finished ? to_run - finished : 0;
  std::string text = std::to_string(summary.ran) + " done, " + std::to_string(summary.failed.size()) +
                     " failed, " + std::to_string(left) + " left";
  if (summary.ran > 0 && left > 0) {
    const double seconds = subject_seconds / static_cast<double>(summary.ran) * static_cast<double>(left) /
                           static_cast<double>(std::min<std::size_t>(left, static_cast<std::size_t>(jobs)));
    const long whole = std::lround(seconds);
    text += ", about " + (whole >= 60 ? std::to_string(whole / 60) + " min " : std::string()) +
            std::to_string(whole % 60) + " s left";
  }
  return text;
}

/// Refuses a batch into a folder that holds anything but a dataset phantasm writes (a batch
/// resumes into its own folder; it must not scatter subjects among unrelated files).
/// Entries of a cache folder whose names start with `prefix`: "anatomy-" (pipeline/anatomy_cache.hpp)
/// or "reference-" (pipeline/reference_cache.hpp).
/// The entries of a cache folder by kind (pipeline/anatomy_cache.hpp, reference_cache.hpp,
/// reference_images_cache.hpp, reference_files_cache.hpp) and their bytes.
struct CacheCounts {
  std::size_t anatomies = 0, states = 0, images = 0, files = 0;
  double bytes = 0.0;
};

CacheCounts cache_counts(const std::filesystem::path& folder) {
  CacheCounts counts;
  std::error_code error;
  if (folder.empty() || !std::filesystem::is_directory(folder, error)) return counts;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    if (entry.path().extension() != ".bin") continue;
    const std::string name = entry.path().filename().string();
    const auto starts = [&](const char* prefix) { return name.rfind(prefix, 0) == 0; };
    counts.anatomies += starts("anatomy-");
    counts.states += starts("reference-");
    counts.images += starts("images-");
    counts.files += starts("file-");
    std::error_code size_error;
    const auto size = entry.file_size(size_error);
    if (!size_error) counts.bytes += static_cast<double>(size);
  }
  return counts;
}

void require_batch_folder(const std::filesystem::path& folder) {
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) return;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    const bool ours = name == "dataset_description.json" || name == "participants.tsv" || name == "README" ||
                      name == "derivatives" || name.rfind("sub-", 0) == 0 || SweepMark::is_mark_name(name) ||
                      is_temporary_file_name(entry.path());
    if (!ours) {
      throw InputError(
          folder.string() +
          ": expected an empty or new output folder, or a dataset an earlier batch wrote, found '" + name +
          "' in it (a file phantasm does not write)");
    }
  }
}

} // namespace

bool subject_is_complete(const std::filesystem::path& output, const SweepSubject& subject) {
  const std::filesystem::path provenance = DatasetLayout(output, subject.id).provenance();
  std::ifstream in(provenance);
  if (!in) return false;
  try {
    const nlohmann::json json = nlohmann::json::parse(in);
    return json.at("scene").at("sha256").get<std::string>() == sha256_hex(subject.scene_text);
  } catch (const std::exception&) {
    return false;
  }
}

bool subject_converged(const std::filesystem::path& output, const SweepSubject& subject) {
  std::ifstream in(DatasetLayout(output, subject.id).provenance());
  if (!in) return true;
  try {
    return nlohmann::json::parse(in).value("converged", true);
  } catch (const std::exception&) {
    return true;
  }
}

BatchSummary run_batch(const Sweep& sweep, const BatchOptions& options, std::ostream& log) {
  if (options.jobs < 1)
    throw InputError("--jobs: expected at least 1, found " + std::to_string(options.jobs));
  BatchSummary summary;
  // Held until the batch returns: shards of a sweep share the folder, a run cannot enter it.
  const OutputFolderLock lock(options.output, FolderLockMode::shared);
  require_batch_folder(options.output);
  const SweepMark mark(options.output, sha256_hex(sweep.name + "\n" + sweep.base_scene.string() + "\n" +
                                                  participants_tsv(sweep))
                                           .substr(0, 16));
  prepare_output_folder(options.output, true);
  write_file_atomically(options.output / "participants.tsv", participants_tsv(sweep));

  std::vector<std::size_t> pending;
  for (std::size_t s = 0; s < sweep.subjects.size(); ++s) {
    if (!options.shard.holds(s)) continue;
    ++summary.in_shard;
    if (subject_is_complete(options.output, sweep.subjects[s])) {
      ++summary.skipped;
    } else {
      pending.push_back(s);
    }
  }
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  int threads = std::max(1, static_cast<int>(hardware) / options.jobs);
  if (const char* set = std::getenv("OMP_NUM_THREADS")) threads = std::max(1, std::atoi(set));
  if (!options.quiet) {
    log << "[batch] " << sweep.name << ": " << summary.in_shard << " of " << sweep.subjects.size()
        << " subjects in shard " << options.shard.index << "/" << options.shard.count << ", "
        << summary.skipped << " already complete, " << pending.size() << " to run, " << options.jobs
        << " at a time with " << threads << " threads each\n";
  }
  const CacheCounts cache_before = cache_counts(options.anatomy_cache);
  std::map<pid_t, Running> running;
  std::size_t next = 0;
  double subject_seconds = 0.0; // summed over the subjects made, for the time left
  const pid_t parent = ::getpid();
  while (true) {
    while (!cancellation_requested() && static_cast<int>(running.size()) < options.jobs &&
           next < pending.size()) {
      const std::size_t s = pending[next++];
      log.flush();
      std::cerr.flush();
      const pid_t child = ::fork();
      if (child < 0) throw std::runtime_error("cannot start a process for subject " + sweep.subjects[s].id);
      if (child == 0)
        run_subject_and_exit(sweep, sweep.subjects[s], options.output, threads, parent, options.strict,
                             options.anatomy_cache);
      running[child] = {s, std::chrono::steady_clock::now()};
    }
    if (running.empty()) break;
    if (cancellation_requested()) {
      for (auto& [pid, job] : running) {
        if (!job.signalled) ::kill(pid, SIGTERM);
        job.signalled = true;
      }
    }
    int status = 0;
    const pid_t done = ::waitpid(-1, &status, WNOHANG);
    if (done <= 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const auto found = running.find(done);
    if (found == running.end()) continue;
    const SweepSubject& subject = sweep.subjects[found->second.subject];
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - found->second.start).count();
    running.erase(found);
    const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (ok) {
      ++summary.ran;
      subject_seconds += seconds;
      if (!options.quiet) {
        log << "[batch] sub-" << subject.id << " done in " << static_cast<int>(seconds * 10) / 10.0 << " s ("
            << batch_status(summary, pending.size(), subject_seconds, options.jobs) << ")\n";
      }
    } else if (cancellation_requested()) {
      summary.interrupted = true;
    } else {
      summary.failed.push_back(subject.id);
      log << "[batch] sub-" << subject.id << " failed ("
          << (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                : "signal " + std::to_string(WTERMSIG(status)))
          << "; " << batch_status(summary, pending.size(), subject_seconds, options.jobs) << ")\n";
    }
  }
  for (std::size_t s = 0; s < sweep.subjects.size(); ++s) {
    if (options.shard.holds(s) && subject_is_complete(options.output, sweep.subjects[s]) &&
        !subject_converged(options.output, sweep.subjects[s]))
      summary.unconverged.push_back(sweep.subjects[s].id);
  }
  if (cancellation_requested()) summary.interrupted = true;
  if (!options.quiet && !options.anatomy_cache.empty()) {
    const CacheCounts after = cache_counts(options.anatomy_cache);
    const auto added = [](std::size_t now, std::size_t before) { return now - std::min(now, before); };
    log << "[batch] anatomy cache " << options.anatomy_cache.string() << ": " << after.anatomies
        << " anatomies, " << added(after.anatomies, cache_before.anatomies)
        << " built by this batch (subjects with the same anatomy settings, inputs and seed share one); "
        << after.states << " reference states, " << added(after.states, cache_before.states)
        << " voxelized by this batch (subjects that also share the grid and the voxelization share one); "
        << after.images << " reference image sets, " << added(after.images, cache_before.images)
        << " made by this batch (subjects that also share the MRI settings share one); " << after.files
        << " reference-session files, " << added(after.files, cache_before.files) << " stored by this batch; "
        << format_bytes(after.bytes) << " in all\n";
  }
  // Processes of an earlier, killed batch may have ended only after this one started (and every
  // subject of this one has ended: what is left of theirs is stale too).
  remove_stale_temporaries(options.output);
  return summary;
}

} // namespace phantasm
