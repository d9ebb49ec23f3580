#include "apps/phantasm/commands.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "io/output_path.hpp"
#include "pipeline/cost_estimate.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <new>
#include <string>
#include <vector>

namespace {

/// 130 after SIGINT, 143 after SIGTERM (the shell's 128 + signal), as if the signal had ended
/// the program, once every file written so far is complete.
int interrupted_exit_code() {
  const int signal_number = phantasm::cancellation_signal();
  return signal_number > 0 ? 128 + signal_number : phantasm::cli::exit_interrupted;
}

/// CLI11 answers an unknown first word with "A subcommand is required", which names neither
/// the word nor what was expected: check the words before the subcommand ourselves.
/// @return the message for an unknown subcommand or top-level option, or for none at all; "" when
/// the arguments are left to CLI11
std::string unknown_top_level_word(const CLI::App& app, int argc, char** argv) {
  std::string names;
  std::vector<std::string> known;
  for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + command->get_name();
    known.push_back(command->get_name());
  }
  for (int a = 1; a < argc; ++a) {
    const std::string word = argv[a];
    if (word == "-h" || word == "--help" || word == "--version") return {};
    if (word.rfind('-', 0) == 0) {
      return "phantasm: unknown option '" + word + "' (before a subcommand only --help and --version are " +
             "known; subcommands: " + names + ")";
    }
    if (std::find(known.begin(), known.end(), word) == known.end())
      return "phantasm: unknown subcommand '" + word + "' (expected one of: " + names +
             "; see phantasm --help)";
    return {};
  }
  return "phantasm: a subcommand is required, one of: " + names + " (see phantasm --help)";
}

} // namespace

namespace phantasm::cli {

MemoryLimit memory_limit(const std::string& max_memory) {
  if (!max_memory.empty()) return {parse_memory_size(max_memory), "(--max-memory)"};
  return {available_memory_bytes(), "available"};
}

} // namespace phantasm::cli

int main(int argc, char** argv) {
  using namespace phantasm::cli;
  phantasm::install_cancellation_handlers(true);

  CLI::App app{"phantasm: deformable anatomical MRI phantoms with exact ground truth", "phantasm"};
  app.set_version_flag("--version", std::string("phantasm ") + phantasm::version);
  app.require_subcommand(1);
  std::function<int()> action;
  add_run_command(app, action);
  add_batch_command(app, action);
  add_hdf5_command(app, action);
  add_atlas_command(app, action);
  add_validate_command(app, action);
  add_info_command(app, action);
  add_eval_command(app, action);
  add_task_command(app, action);
  add_pair_command(app, action);
  add_report_command(app, action);

  if (const std::string unknown = unknown_top_level_word(app, argc, argv); !unknown.empty()) {
    std::cerr << unknown << '\n';
    return exit_bad_input;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? exit_ok : exit_bad_input;
  }
  try {
    const int code = action();
    return code == exit_interrupted ? interrupted_exit_code() : code;
  } catch (const phantasm::Cancelled&) {
    std::cerr << "phantasm: interrupted; every file written so far is complete\n";
    return interrupted_exit_code();
  } catch (const phantasm::InputError& error) {
    std::cerr << error.what() << '\n';
    return exit_bad_input;
  } catch (const std::bad_alloc&) {
    // What ran out is the grid, the meshes or the sweep the inputs asked for.
    std::cerr
        << "phantasm: error: out of memory: expected inputs that fit in this machine's memory (a coarser "
           "grid, fewer or smaller meshes, a smaller sweep), found more than it holds\n";
    return exit_failure;
  } catch (const std::filesystem::filesystem_error& error) {
    // A folder to be made where the user's output holds a file ("--force" into a folder whose
    // sub-01 is a file): the user's to fix, and the file in the way is what to name.
    if (const std::string message = phantasm::file_in_the_way_message(error); !message.empty()) {
      std::cerr << message << '\n';
      return exit_bad_input;
    }
    // The library's message ("filesystem error: cannot rename: ...") said what failed, not where.
    std::cerr << "phantasm: error: " << error.path1().string() << ": " << error.code().message();
    if (!error.path2().empty()) std::cerr << " (with " << error.path2().string() << ")";
    std::cerr << '\n';
    return exit_failure;
  } catch (const std::exception& error) {
    std::cerr << "phantasm: error: " << error.what() << '\n';
    return exit_failure;
  }
}
