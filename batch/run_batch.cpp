#include "batch/run_batch.hpp"

#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "io/output_path.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/run_pipeline.hpp"

#include <malloc.h>
#include <nlohmann/json.hpp>
#include <omp.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <new>
#include <thread>

namespace phantasm {
namespace {

/// One subject in this process: phantasm's exit code for it (0 made, 1 failed, 2 bad input,
/// 128 + signal cancelled); its error is printed.
int run_subject(const Sweep& sweep, const SweepSubject& subject, const std::filesystem::path& output,
                bool strict, const std::filesystem::path& anatomy_cache) {
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
  if (code == 0 && cancellation_requested())
    code = 128 + (cancellation_signal() > 0 ? cancellation_signal() : SIGINT);
  std::cerr.flush();
  return code;
}

/// What a worker is asked (a subject's index, or k_stop) and what it answers.
constexpr std::uint64_t k_stop = ~std::uint64_t{0};
struct Answer {
  std::uint64_t subject;
  std::int32_t code;
};

/// A worker's whole life: subjects sent on `channel` one at a time, each answered with its exit
/// code, until k_stop, the end of the channel, or a signal. One process makes the subjects of its
/// job slot one after the other, so the memory it freed is reused without the kernel clearing it
/// again, and the subjects' freed memory stays with the process (mallopt below) rather than going
/// back to the kernel between subjects: large blocks too (the images' transforms, the grids), which
/// malloc would otherwise map afresh for each subject and the kernel clear page by page. A
/// subject's failure is answered and the next one runs; a crash ends the worker, and the batch
/// counts its subject as failed and starts another.
[[noreturn]] void work_and_exit(const Sweep& sweep, const std::filesystem::path& output, int threads,
                                pid_t parent, bool strict, const std::filesystem::path& anatomy_cache,
                                int channel) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL); // a batch killed outright takes its subjects with it
  if (::getppid() != parent) ::_exit(1);
  // SIGINT from the terminal reaches the subject and the batch, which then sends SIGTERM: a
  // subject counts every signal as a request to stop, so it always cleans up before it exits.
  install_cancellation_handlers(false);
  omp_set_num_threads(threads);
  ::mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
  ::mallopt(M_MMAP_THRESHOLD, 32 << 20);
  ::mallopt(M_MMAP_MAX, 0);
  while (true) {
    pollfd wait{channel, POLLIN, 0};
    const int ready = ::poll(&wait, 1, 100);
    if (cancellation_requested()) ::_exit(128 + (cancellation_signal() > 0 ? cancellation_signal() : SIGINT));
    if (ready <= 0) continue;
    std::uint64_t index = k_stop;
    if (::recv(channel, &index, sizeof index, MSG_WAITALL) != static_cast<ssize_t>(sizeof index) ||
        index == k_stop || index >= sweep.subjects.size())
      ::_exit(0);
    const int code = run_subject(sweep, sweep.subjects[index], output, strict, anatomy_cache);
    if (code >= 128) ::_exit(code);
    Answer answer;
    std::memset(&answer, 0, sizeof answer); // no padding byte left unwritten
    answer.subject = index;
    answer.code = code;
    if (::send(channel, &answer, sizeof answer, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof answer))
      ::_exit(1);
  }
}

/// The batch's side of one worker process.
struct Worker {
  pid_t pid = -1;
  int channel = -1;        ///< the batch's end of the worker's socket
  std::size_t subject = 0; ///< the subject it makes, when busy
  bool busy = false;
  std::chrono::steady_clock::time_point start;
  bool signalled = false; ///< asked to stop once (a second signal would end it before it cleans up)
};

/// The batch's job processes: one per job slot, started when there is a subject for it, each
/// sent one subject at a time (work_and_exit).
class JobSlots {
public:
  /// Called as each subject ends: its index, seconds, whether it was made, and how it ended.
  using Finished = std::function<void(std::size_t, double, bool, const std::string&)>;

  JobSlots(const Sweep& sweep, const BatchOptions& options, int threads, std::ostream& log)
      : m_sweep(sweep), m_options(options), m_threads(threads), m_log(log), m_parent(::getpid()) {}
  ~JobSlots() {
    for (Worker& worker : m_workers)
      close_channel(worker);
  }
  JobSlots(const JobSlots&) = delete;
  JobSlots& operator=(const JobSlots&) = delete;

  /// Sends the queue's first subjects to idle processes, starting processes up to --jobs.
  void hand_out(std::deque<std::size_t>& queue) {
    std::size_t alive = 0, idle = 0;
    for (const Worker& worker : m_workers) {
      alive += worker.channel >= 0;
      idle += worker.channel >= 0 && !worker.busy;
    }
    for (; alive < static_cast<std::size_t>(m_options.jobs) && idle < queue.size(); ++alive, ++idle)
      start();
    for (Worker& worker : m_workers) {
      if (worker.channel < 0 || worker.busy || queue.empty()) continue;
      const std::uint64_t index = queue.front();
      if (::send(worker.channel, &index, sizeof index, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof index)) {
        close_channel(worker); // it ended while idle: reaped by wait(), its subject goes to another
        continue;
      }
      queue.pop_front();
      worker.subject = index;
      worker.busy = true;
      worker.start = std::chrono::steady_clock::now();
    }
  }

  /// Ends the idle processes when `idle_end` (nothing left, or the batch stops); when `stopping`,
  /// asks each busy one to stop, once (a second signal would end it before it cleans up).
  void end_idle(bool idle_end, bool stopping) {
    for (Worker& worker : m_workers) {
      if (worker.busy) {
        if (stopping && !worker.signalled) ::kill(worker.pid, SIGTERM);
        worker.signalled = worker.signalled || stopping;
      } else if (worker.channel >= 0 && idle_end) {
        const std::uint64_t stop = k_stop;
        [[maybe_unused]] const ssize_t sent = ::send(worker.channel, &stop, sizeof stop, MSG_NOSIGNAL);
        close_channel(worker);
      }
    }
  }

  bool empty() const { return m_workers.empty(); }

  /// Waits up to 20 ms for the busy processes' answers, then reaps the processes that ended: a
  /// busy one's subject failed (a crash, the kernel's out-of-memory killer) or was interrupted.
  void wait(const Finished& finished) {
    std::vector<pollfd> waits;
    for (const Worker& worker : m_workers)
      if (worker.busy && worker.channel >= 0) waits.push_back({worker.channel, POLLIN, 0});
    if (waits.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    } else if (::poll(waits.data(), waits.size(), 20) > 0) {
      for (const pollfd& wait : waits) {
        if (wait.revents == 0) continue;
        Worker& worker = *std::find_if(m_workers.begin(), m_workers.end(),
                                       [&](const Worker& w) { return w.channel == wait.fd; });
        Answer answer{};
        if (::recv(worker.channel, &answer, sizeof answer, MSG_WAITALL) ==
                static_cast<ssize_t>(sizeof answer) &&
            answer.subject == worker.subject) {
          worker.busy = false;
          finished(worker.subject, seconds_since(worker.start), answer.code == 0,
                   "exit " + std::to_string(answer.code));
        } else {
          close_channel(worker); // it ended while making its subject: its exit status says how
        }
      }
    }
    int status = 0;
    for (pid_t done; (done = ::waitpid(-1, &status, WNOHANG)) > 0;) {
      const auto found =
          std::find_if(m_workers.begin(), m_workers.end(), [&](const Worker& w) { return w.pid == done; });
      if (found == m_workers.end()) continue;
      if (found->busy) {
        finished(found->subject, seconds_since(found->start), false,
                 WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                   : "signal " + std::to_string(WTERMSIG(status)));
      }
      close_channel(*found);
      m_workers.erase(found);
    }
  }

private:
  static void close_channel(Worker& worker) {
    if (worker.channel >= 0) ::close(worker.channel);
    worker.channel = -1;
  }
  static double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  void start() {
    int ends[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, ends) != 0)
      throw std::runtime_error(std::string("cannot start a process for the subjects: ") +
                               std::strerror(errno));
    m_log.flush();
    std::cerr.flush();
    const pid_t child = ::fork();
    if (child < 0) {
      ::close(ends[0]);
      ::close(ends[1]);
      throw std::runtime_error(std::string("cannot start a process for the subjects: ") +
                               std::strerror(errno));
    }
    if (child == 0) {
      // The other workers' channels stay theirs: a copy here would hide their end from them.
      for (const Worker& other : m_workers)
        if (other.channel >= 0) ::close(other.channel);
      ::close(ends[0]);
      work_and_exit(m_sweep, m_options.output, m_threads, m_parent, m_options.strict, m_options.anatomy_cache,
                    ends[1]);
    }
    ::close(ends[1]);
    Worker worker;
    worker.pid = child;
    worker.channel = ends[0];
    m_workers.push_back(worker);
  }

  const Sweep& m_sweep;
  const BatchOptions& m_options;
  int m_threads;
  std::ostream& m_log;
  pid_t m_parent;
  std::vector<Worker> m_workers;
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
  std::deque<std::size_t> queue(pending.begin(), pending.end());
  double subject_seconds = 0.0; // summed over the subjects made, for the time left
  const auto finished = [&](std::size_t s, double seconds, bool ok, const std::string& how) {
    const SweepSubject& subject = sweep.subjects[s];
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
      log << "[batch] sub-" << subject.id << " failed (" << how << "; "
          << batch_status(summary, pending.size(), subject_seconds, options.jobs) << ")\n";
    }
  };
  JobSlots slots(sweep, options, threads, log);
  while (true) {
    const bool stopping = cancellation_requested();
    if (!stopping) slots.hand_out(queue);
    slots.end_idle(stopping || queue.empty(), stopping);
    if (slots.empty()) break;
    slots.wait(finished);
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
