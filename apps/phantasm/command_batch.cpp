#include "apps/phantasm/commands.hpp"
#include "batch/run_batch.hpp"
#include "io/atomic_file.hpp"
#include "io/dataset_layout.hpp"
#include "pipeline/cost_estimate.hpp"
#include "report/dataset_page.hpp"

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>

namespace phantasm::cli {
namespace {

/// Refuses, before any subject runs, a sweep whose largest subject of this shard needs more
/// memory times the jobs that run at once than the machine has (at most 1000 subjects are
/// estimated: the first ones, as a sweep's grid varies its last key fastest).
void check_sweep_memory(const Sweep& sweep, const Shard& shard, int jobs, const MemoryLimit& limit) {
  if (limit.bytes <= 0.0) return;
  std::optional<CostEstimate> largest;
  std::string largest_id;
  std::size_t in_shard = 0, estimated = 0;
  for (std::size_t s = 0; s < sweep.subjects.size(); ++s) {
    if (!shard.holds(s)) continue;
    ++in_shard;
    if (estimated >= 1000) continue;
    ++estimated;
    const SceneLoadResult loaded = parse_scene(sweep.subjects[s].scene_text, sweep.base_scene);
    if (!loaded.scene) continue; // the batch reports it as the subject's failure
    CostEstimate estimate = estimate_cost(*loaded.scene);
    if (!largest || estimate.peak_memory_bytes > largest->peak_memory_bytes) {
      largest = std::move(estimate);
      largest_id = sweep.subjects[s].id;
    }
  }
  if (!largest) return;
  const int copies = static_cast<int>(std::min<std::size_t>(in_shard, static_cast<std::size_t>(jobs)));
  check_memory(*largest, limit.bytes, limit.source, sweep.file.string() + ": sub-" + largest_id, copies);
}

} // namespace

void add_batch_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string sweep;
    std::string output = "out";
    int jobs = 1;
    std::string shard = "1/1";
    bool quiet = false;
    bool list = false;
    bool strict = false;
    std::string cache;
    bool no_cache = false;
    std::string max_memory;
    int write_delay_ms = 0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "batch", "Run every subject of a sweep into one dataset; restart to finish an interrupted batch");
  command->add_option("sweep", options->sweep, "Sweep file (YAML, docs/batch.md)")->required();
  command->add_option("-o,--output", options->output, "Dataset folder")->capture_default_str();
  command->add_option("-j,--jobs", options->jobs, "Subjects run at once on this machine")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  command->add_option("--shard", options->shard, "Run the i-th of N disjoint slices of the sweep (i/N)")
      ->capture_default_str();
  command->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  command->add_flag(
      "--strict", options->strict,
      "A subject whose run warns (a solve that did not converge, inverted tets, a Jacobian <= 0 "
      "inside an exact mask) fails and is not written");
  command->add_option(
      "--cache", options->cache,
      "Anatomy cache folder: subjects with the same anatomy settings, inputs and seed fit and "
      "mesh it once, with the same grid and voxelization voxelize the reference state once, and "
      "with the same MRI settings make the reference state's images and its session's files once "
      "(default: derivatives/phantasm/cache in the dataset)");
  command->add_flag("--no-cache", options->no_cache, "Build every subject's anatomy and reference state anew")
      ->excludes("--cache");
  command->add_option("--max-memory", options->max_memory,
                      "Refuse a sweep whose largest subject's estimated peak memory times --jobs exceeds "
                      "this (4G, 512M; default: the memory available)");
  command->add_flag("--list", options->list,
                    "Print the sweep's subject labels, one per line in sweep order, and run nothing");
  // For tests that interrupt a batch while it writes; hidden from --help.
  command->add_option("--write-delay-ms", options->write_delay_ms)->group("")->check(CLI::NonNegativeNumber);
  command->callback([options, &action] {
    action = [options] {
      const auto start = std::chrono::steady_clock::now();
      set_write_delay_for_testing(options->write_delay_ms);
      const Shard shard = parse_shard(options->shard);
      const Sweep sweep = load_sweep(options->sweep, options->list ? SweepDepth::labels : SweepDepth::full);
      if (options->list) {
        for (const auto& subject : sweep.subjects)
          std::cout << subject.id << '\n';
        return static_cast<int>(exit_ok);
      }
      check_sweep_memory(sweep, shard, options->jobs, memory_limit(options->max_memory));
      BatchOptions batch_options;
      batch_options.output = options->output;
      batch_options.jobs = options->jobs;
      batch_options.shard = shard;
      batch_options.quiet = options->quiet;
      batch_options.strict = options->strict;
      if (!options->no_cache) {
        batch_options.anatomy_cache = options->cache.empty() ? dataset_anatomy_cache(options->output)
                                                             : std::filesystem::path(options->cache);
      }
      const BatchSummary summary = run_batch(sweep, batch_options, std::cerr);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (summary.interrupted) {
        std::cerr << "phantasm: batch interrupted; complete subjects stay, run the batch again to finish\n";
        return static_cast<int>(exit_interrupted);
      }
      // The dataset's page (derivatives/phantasm/index.html): every subject made so far, by any shard.
      try {
        const std::filesystem::path page = write_dataset_page(options->output);
        if (!options->quiet) std::cerr << "[batch] wrote " << page.string() << "\n";
      } catch (const std::exception& error) {
        std::cerr << "phantasm: warning: the dataset page was not written: " << error.what() << '\n';
      }
      if (!options->quiet || !summary.failed.empty()) {
        std::cerr << "[batch] " << summary.ran << " subjects made, " << summary.skipped
                  << " already complete, " << summary.failed.size() << " failed, in "
                  << static_cast<int>(seconds) << " s\n";
      }
      if (!summary.unconverged.empty()) {
        std::string list;
        for (const auto& id : summary.unconverged)
          list += " sub-" + id;
        std::cerr << "[batch] warning: " << summary.unconverged.size()
                  << " subjects with a solve that did not converge (provenance.json, solves):" << list
                  << '\n';
      }
      if (!summary.failed.empty()) {
        std::string list;
        for (const auto& id : summary.failed)
          list += " sub-" + id;
        std::cerr << "phantasm: failed:" << list << " (messages above); run the batch again to retry them\n";
        return static_cast<int>(exit_failure);
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
