#include "apps/phantasm/commands.hpp"
#include "core/progress.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"
#include "pipeline/cost_estimate.hpp"
#include "pipeline/run_pipeline.hpp"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_run_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string scene;
    std::string output = "out";
    bool force = false;
    bool quiet = false;
    bool strict = false;
    int write_delay_ms = 0;
    std::string cache;
    std::string max_memory;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "run", "Run a scene through every stage and write the dataset (BIDS-like, see docs/architecture.md)");
  command->add_option("scene", options->scene, "Scene file (YAML)")->required();
  command->add_option("-o,--output", options->output, "Dataset folder to write")->capture_default_str();
  command->add_flag("--force", options->force, "Write into a folder that already holds files");
  command->add_flag("-q,--quiet", options->quiet, "Print nothing but errors and warnings");
  command->add_flag(
      "--strict", options->strict,
      "A warning (a solve that did not converge, inverted tets, a Jacobian <= 0 inside an exact "
      "mask) is an error: exit 1, nothing of the subject written");
  command->add_option("--cache", options->cache,
                      "Anatomy cache folder: a run whose anatomy settings, inputs and seed match an earlier "
                      "one's reads its organs from there instead of fitting and meshing them again; "
                      "with the same grid and voxelization its voxelized reference state too, and with "
                      "the same MRI settings the reference state's images and its session's files");
  command->add_option("--max-memory", options->max_memory,
                      "Refuse a scene whose estimated peak memory exceeds this (4G, 512M; default: the "
                      "memory available, MemAvailable and the cgroup's limit)");
  // For tests that interrupt a run while it writes; hidden from --help.
  command->add_option("--write-delay-ms", options->write_delay_ms)->group("")->check(CLI::NonNegativeNumber);
  command->callback([options, &action] {
    action = [options] {
      const auto start = std::chrono::steady_clock::now();
      const SceneLoadResult result = load_scene(options->scene);
      if (!result.scene) {
        std::cerr << format_diagnostics(result.problems);
        return static_cast<int>(exit_bad_input);
      }
      // The cost before the work: a scene that would not fit is refused before anything is
      // made or written (not even the output folder).
      const MemoryLimit limit = memory_limit(options->max_memory);
      check_memory(estimate_cost(*result.scene), limit.bytes, limit.source, options->scene);
      set_write_delay_for_testing(options->write_delay_ms);
      Reporter reporter(std::cerr, progress_style_for(STDERR_FILENO, options->quiet));
      // One writer per dataset, from before the folder is checked until the last file is written.
      const bool existed = std::filesystem::exists(options->output);
      const OutputFolderLock lock(options->output);
      RunOptions run_options;
      run_options.output = options->output;
      run_options.force = options->force;
      run_options.output_created = !existed;
      run_options.strict = options->strict;
      run_options.anatomy_cache = options->cache;
      const RunSummary summary = run_scene(*result.scene, run_options, reporter);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      reporter.note("wrote " + std::to_string(summary.files.size()) + " files to " + options->output +
                    " in " + std::to_string(seconds).substr(0, 5) + " s");
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
