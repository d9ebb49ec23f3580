#include "apps/phantasm/commands.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"
#include "report/benchmark_page.hpp"
#include "report/dataset_page.hpp"
#include "report/subject_report.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_report_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, subject, output;
    std::vector<std::string> scores;
    bool quiet = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "report",
      "Write the HTML report of every subject of a dataset written earlier, "
      "derivatives/phantasm/sub-<id>.html, and the dataset's page, derivatives/phantasm/index.html; "
      "or, with --scores, a benchmark page of methods side by side (docs/report.md)");
  auto* dataset =
      command->add_option("dataset", options->dataset, "Dataset folder written by phantasm run or batch");
  auto* subject =
      command->add_option("--subject", options->subject, "Only this subject (its label, without sub-)");
  auto* scores = command->add_option("--scores", options->scores,
                                     "Instead of a dataset: the scores of a method (phantasm eval TASK "
                                     "--results DIR --json FILE); repeat it "
                                     "to compare methods on one page");
  auto* output =
      command->add_option("-o,--output", options->output, "With --scores: the page to write (HTML)");
  scores->excludes(dataset)->excludes(subject)->needs(output);
  output->needs(scores);
  command->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
  command->callback([options, &action] {
    if (options->dataset.empty() && options->scores.empty())
      throw CLI::RequiredError("dataset (or --scores)");
    action = [options] {
      if (!options->scores.empty()) {
        require_replaceable_file(options->output, "--output");
        const std::vector<std::filesystem::path> files(options->scores.begin(), options->scores.end());
        write_file_atomically(options->output, benchmark_page_html(read_method_scores(files)));
        if (!options->quiet) std::cerr << "[report] wrote " << options->output << "\n";
        return static_cast<int>(exit_ok);
      }
      const DatasetReportSummary summary = write_dataset_reports(options->dataset, options->subject);
      const std::filesystem::path page = write_dataset_page(options->dataset);
      if (!options->quiet) {
        for (const auto& path : summary.written)
          std::cerr << "[report] wrote " << path.string() << "\n";
        for (const std::string& failed : summary.failed)
          std::cerr << "[report] sub-" << failed << ": the run did not finish (no provenance.json)\n";
        std::cerr << "[report] wrote " << page.string() << "\n";
      }
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
