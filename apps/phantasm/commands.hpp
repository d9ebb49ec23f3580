// The phantasm command's exit codes and its subcommands (run, validate, info, eval, batch,
// hdf5), each registered on the CLI11 app by its own file.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace phantasm::cli {

/// Exit codes of the phantasm command.
enum ExitCode : int {
  exit_ok = 0,
  exit_failure = 1,       ///< a fault of the program or the system (disk full, ...)
  exit_bad_input = 2,     ///< the scene or another input is wrong; the message says where
  exit_interrupted = 130, ///< SIGINT (143 after SIGTERM); nothing half-written is left
};

/// The memory a run may use: --max-memory when given, else what the machine has available.
struct MemoryLimit {
  double bytes = 0.0; ///< 0: unknown (no check)
  std::string source; ///< "(--max-memory)" or "available"
};
/// @param max_memory the --max-memory text, empty when not given
/// @throws InputError for a size that does not parse
MemoryLimit memory_limit(const std::string& max_memory);

/// Each subcommand registers itself and sets the action run after parsing.
void add_run_command(CLI::App& app, std::function<int()>& action);
void add_validate_command(CLI::App& app, std::function<int()>& action);
void add_info_command(CLI::App& app, std::function<int()>& action);
void add_eval_command(CLI::App& app, std::function<int()>& action);
void add_batch_command(CLI::App& app, std::function<int()>& action);
void add_hdf5_command(CLI::App& app, std::function<int()>& action);
void add_atlas_command(CLI::App& app, std::function<int()>& action);
void add_task_command(CLI::App& app, std::function<int()>& action);
void add_pair_command(CLI::App& app, std::function<int()>& action);
void add_report_command(CLI::App& app, std::function<int()>& action);

} // namespace phantasm::cli
