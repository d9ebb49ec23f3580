#include "apps/phantasm/commands.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/version.hpp"

#include <csignal>
#include <iostream>

namespace {

extern "C" void on_interrupt(int signal_number) {
  phantasm::request_cancellation();
  // A second interrupt ends the program at once.
  std::signal(signal_number, SIG_DFL);
}

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm::cli;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);

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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? exit_ok : exit_bad_input;
  }
  try {
    return action();
  } catch (const phantasm::Cancelled&) {
    std::cerr << "phantasm: interrupted; every file written so far is complete\n";
    return exit_interrupted;
  } catch (const phantasm::InputError& error) {
    std::cerr << error.what() << '\n';
    return exit_bad_input;
  } catch (const std::exception& error) {
    std::cerr << "phantasm: error: " << error.what() << '\n';
    return exit_failure;
  }
}
