// Running a sweep's subjects into one dataset: shards, parallel child processes, and the skip of
// subjects already complete, so a killed batch resumes where it stopped.
#pragma once

#include "batch/sweep.hpp"

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace phantasm {

struct BatchOptions {
  std::filesystem::path output; ///< the dataset folder all subjects go into
  int jobs = 1;                 ///< subjects run at once, each in its own process
  Shard shard;                  ///< which slice of the sweep this batch makes
  bool quiet = false;
  bool strict = false; ///< a subject whose run warned (unconverged solve, inverted tets) fails, unwritten
  /// the subjects' anatomy cache (pipeline/anatomy_cache.hpp), shared by every subject, job and
  /// shard; empty: none
  std::filesystem::path anatomy_cache;
};

struct BatchSummary {
  std::size_t in_shard = 0, skipped = 0, ran = 0;
  std::vector<std::string> failed; ///< subject ids
  /// subjects of the shard (made or already complete) with a solve that did not converge
  std::vector<std::string> unconverged;
  bool interrupted = false;
};

/// True when a subject is complete in `output`: its provenance.json (written last) exists and
/// records the hash of this subject's scene.
bool subject_is_complete(const std::filesystem::path& output, const SweepSubject& subject);

/// False when a complete subject's provenance.json records a solve that did not converge.
bool subject_converged(const std::filesystem::path& output, const SweepSubject& subject);

/// Runs the sweep's subjects of one shard into one dataset: participants.tsv first (the same
/// bytes from every shard), then the subjects that are not complete yet, `jobs` at a time, in
/// one child process per job slot (fork; the children die with the batch), each with hardware
/// threads / jobs OpenMP threads (OMP_NUM_THREADS when set) and making its subjects one after
/// the other. A subject that fails is reported and its process goes on; a process that dies
/// while making a subject fails that subject, and another process takes the rest. Outputs do not depend on
/// jobs, shard or thread count, so shards on several machines fill one dataset. A batch killed at any moment
/// and started again skips the complete subjects and remakes the others (files are written atomically; a
/// subject's temporary files from a killed process are removed). SIGINT/SIGTERM stop the children and return
/// with `interrupted`.
BatchSummary run_batch(const Sweep& sweep, const BatchOptions& options, std::ostream& log);

} // namespace phantasm
