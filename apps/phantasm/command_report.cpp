#include "apps/phantasm/commands.hpp"
#include "report/subject_report.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_report_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, subject;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command =
      app.add_subcommand("report", "Write the HTML report of every subject of a dataset written earlier, "
                                   "derivatives/phantasm/sub-<id>.html (docs/report.md)");
  command->add_option("dataset", options->dataset, "Dataset folder written by phantasm run or batch")
      ->required();
  command->add_option("--subject", options->subject, "Only this subject (its label, without sub-)");
  command->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  command->callback([options, &action] {
    action = [options] {
      const DatasetReportSummary summary = write_dataset_reports(options->dataset, options->subject);
      if (!options->quiet) {
        for (const auto& path : summary.written)
          std::cerr << "[report] wrote " << path.string() << "\n";
        for (const std::string& subject : summary.failed)
          std::cerr << "[report] sub-" << subject << ": the run did not finish (no provenance.json)\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
