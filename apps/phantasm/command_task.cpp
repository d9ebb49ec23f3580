#include "apps/phantasm/commands.hpp"
#include "evaluation/learn2reg_task.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_task_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, task, truth, name = "PHANTASM", fixed_contrast, moving_contrast;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "task", "Make a Learn2Reg-format registration task (and its hidden ground truth) from a dataset");
  command->add_option("dataset", options->dataset, "Dataset folder written by phantasm run or batch")
      ->required();
  command->add_option("-o,--output", options->task, "Task folder to make (new or empty)")->required();
  command->add_option("--truth", options->truth,
                      "Ground-truth folder to make (default: TASK-truth beside it)");
  command->add_option("--name", options->name, "Task name, the prefix of its files (letters and digits)");
  command->add_option("--fixed-contrast", options->fixed_contrast,
                      "Contrast of the fixed images, reference state (default T1w)");
  command->add_option("--moving-contrast", options->moving_contrast,
                      "Contrast of the moving images, deformed state (default: the fixed contrast)");
  command->add_flag("-q,--quiet", options->quiet, "Do not print the pairs");
  command->callback([options, &action] {
    action = [options] {
      TaskRequest request;
      request.dataset = options->dataset;
      request.task = options->task;
      request.truth = options->truth.empty() ? default_truth_folder(options->task)
                                             : std::filesystem::path(options->truth);
      request.name = options->name;
      request.fixed_contrast = options->fixed_contrast;
      request.moving_contrast = options->moving_contrast;
      const nlohmann::json made = make_learn2reg_task(request);
      if (!options->quiet) {
        std::cout << "task " << made["task"].get<std::string>() << " (ground truth in "
                  << made["truth"].get<std::string>() << "), " << made["pairs"].size() << " pairs:\n";
        for (const auto& pair : made["pairs"])
          std::cout << "  " << pair["fixed"].get<std::string>() << " <- " << pair["moving"].get<std::string>()
                    << "  (sub-" << pair["subject"].get<std::string>() << ")\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
