// The page of a registration benchmark: the scores `phantasm eval TASK --results DIR` computes
// (evaluation/score_task.hpp), for one method or several side by side: a summary per method with
// the 30th-percentile robustness figure, plots of mean Dice, HD95, TRE, NDV and folding against
// each varied factor, the scores per structure and per pair, the warnings. docs/report.md.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// One method's scores of a task.
struct MethodScores {
  std::string method; ///< the name shown (its results folder's name)
  nlohmann::json scores;
};

/// The name a method's scores are shown under: the last part of its "results" folder.
std::string method_name(const nlohmann::json& scores);

/// Each structure's mean Dice and HD95 over the pairs that hold it, by name.
struct StructureScore {
  std::string name;
  std::size_t pairs = 0;
  double mean_dice = 0.0, lowest_dice = 0.0, mean_hd95_mm = 0.0; ///< NaN when no pair gave a value
};
std::vector<StructureScore> structure_scores(const nlohmann::json& scores);

/// The page's HTML (self-contained, no script); every text from the scores is HTML-escaped.
/// @throws InputError when a scores object lacks what `phantasm eval` writes (names the method)
std::string benchmark_page_html(const std::vector<MethodScores>& methods);

/// Reads scores JSON files (`phantasm eval TASK --results DIR --json FILE`) for one page.
/// @throws InputError naming the file that is not such scores, or whose task differs from the
///         first file's
std::vector<MethodScores> read_method_scores(const std::vector<std::filesystem::path>& files);

} // namespace phantasm
