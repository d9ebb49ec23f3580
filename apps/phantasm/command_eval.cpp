#include "apps/phantasm/commands.hpp"
#include "core/error.hpp"
#include "core/safe_name.hpp"
#include "evaluation/evaluate_registration.hpp"
#include "evaluation/field_conventions.hpp"
#include "evaluation/learn2reg_task.hpp"
#include "evaluation/score_task.hpp"
#include "io/atomic_file.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"
#include "io/output_path.hpp"
#include "report/benchmark_page.hpp"

#include <iostream>
#include <memory>

namespace phantasm::cli {

void add_eval_command(CLI::App& app, std::function<int()>& action) {
  struct Options {
    std::string dataset, field, labels, json, subject, fixed = "ref";
    std::string results, truth, csv, html, convention = "learn2reg";
    bool identity = false, quiet = false;
    int read_delay_ms = 0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "eval", "Evaluate a registration result against a dataset's ground truth (TRE, Dice, HD95, endpoint "
              "error, Jacobian)");
  command
      ->add_option("dataset", options->dataset,
                   "Dataset folder written by phantasm run (with --results: a task folder of phantasm task)")
      ->required();
  auto* field = command->add_option(
      "--field", options->field, "Displacement field on the fixed grid (ITK/elastix convention, 5-D NIfTI)");
  auto* labels =
      command->add_option("--labels", options->labels, "Moving label map warped onto the fixed grid");
  auto* identity =
      command->add_flag("--identity", options->identity, "Evaluate no registration (the baseline)");
  field->excludes(labels)->excludes(identity);
  labels->excludes(identity);
  command->add_option("--json", options->json, "Write the evaluation as JSON to this file");
  auto* subject =
      command->add_option("--subject", options->subject, "Subject label when the dataset holds several");
  auto* fixed =
      command->add_option("--fixed", options->fixed, "Session of the fixed image: ref (default) or def")
          ->check(CLI::IsMember({"ref", "def"}));
  auto* results = command->add_option("--results", options->results,
                                      "Score a task (the positional folder, made by phantasm task): one "
                                      "disp_<fixed>_<moving>.nii.gz per pair");
  results->excludes(field)->excludes(labels)->excludes(identity)->excludes(subject)->excludes(fixed);
  auto* truth = command->add_option("--truth", options->truth,
                                    "The task's ground-truth folder (default: TASK-truth beside it)");
  auto* convention = command->add_option("--convention", options->convention,
                                         field_convention_help(FieldConvention::learn2reg));
  auto* csv =
      command->add_option("--csv", options->csv, "Write a task's scores per pair as CSV to this file");
  auto* html = command->add_option(
      "--html", options->html,
      "Write a task's scores as a page to this file: per pair, per structure, against each varied factor "
      "(docs/report.md)");
  // A task's options mean nothing without --results (and a subject's nothing with it): refused,
  // not ignored.
  truth->needs(results);
  convention->needs(results);
  csv->needs(results);
  html->needs(results);
  command->add_flag("-q,--quiet", options->quiet, "Do not print the table");
  // For tests that interrupt an evaluation while it reads; hidden from --help.
  command->add_option("--read-delay-ms", options->read_delay_ms)->group("")->check(CLI::NonNegativeNumber);
  command->callback([options, &action] {
    action = [options] {
      set_read_delay_for_testing(options->read_delay_ms);
      // The subject label becomes part of the paths read: it obeys the scene's name rule.
      if (!options->subject.empty() && !is_safe_name(options->subject)) {
        throw InputError(std::string("--subject: expected ") + k_safe_name_rule +
                         " (the label after sub-), found " + quote_name(options->subject));
      }
      if (!options->json.empty()) require_replaceable_file(options->json, "--json");
      if (!options->results.empty()) {
        if (!options->csv.empty()) require_replaceable_file(options->csv, "--csv");
        if (!options->html.empty()) require_replaceable_file(options->html, "--html");
        TaskScoreRequest task;
        task.task = options->dataset;
        task.results = options->results;
        task.truth = options->truth.empty() ? default_truth_folder(options->dataset)
                                            : std::filesystem::path(options->truth);
        task.convention = field_convention_from_string(options->convention, "--convention");
        const nlohmann::json scores = score_task(task);
        const std::string page =
            options->html.empty() ? std::string() : benchmark_page_html({{method_name(scores), scores}});
        if (!options->json.empty()) write_json_file(options->json, scores);
        if (!options->csv.empty()) write_file_atomically(options->csv, task_scores_csv(scores));
        if (!options->html.empty()) write_file_atomically(options->html, page);
        if (!options->quiet) std::cout << task_scores_table(scores);
        for (const auto& warning : scores["warnings"])
          std::cerr << "phantasm: warning: " << warning.get<std::string>() << '\n';
        return static_cast<int>(exit_ok);
      }
      EvaluationRequest request;
      request.dataset = options->dataset;
      request.subject = options->subject;
      request.fixed_session = options->fixed;
      if (!options->field.empty()) request.field = options->field;
      if (!options->labels.empty()) request.warped_labels = options->labels;
      request.identity = options->identity;
      const nlohmann::json evaluation = evaluate_registration(request);
      if (!options->json.empty()) write_json_file(options->json, evaluation);
      if (!options->quiet) std::cout << evaluation_table(evaluation);
      return static_cast<int>(exit_ok);
    };
  });
}

} // namespace phantasm::cli
