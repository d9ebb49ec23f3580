// Evaluating a registration result against a phantasm dataset's ground truth (landmark TRE,
// Dice and HD95, endpoint error, Jacobian), as `phantasm eval` reports it in JSON.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace phantasm {

/// What to evaluate: a phantasm dataset (one subject) and one registration result.
struct EvaluationRequest {
  std::filesystem::path dataset;     ///< the folder `phantasm run -o` wrote
  std::string subject;               ///< BIDS label; empty: the dataset's only subject
  std::string fixed_session = "ref"; ///< "ref" or "def": the registration's fixed image
  /// Exactly one of these three: a displacement field in the ITK/elastix convention on the
  /// fixed grid, a moving label map already warped onto the fixed grid, or the identity (the
  /// "no registration" baseline).
  std::optional<std::filesystem::path> field;
  std::optional<std::filesystem::path> warped_labels;
  bool identity = false;
};

/// Registration metrics against the subject's ground truth: target registration error on the
/// landmarks (fixed landmarks carried by the result against the moving ones), Dice and HD95 per
/// label (the moving labels warped by the result, or the given warped labels, against the fixed
/// labels), dense endpoint error against the ground-truth field inside its exact mask, and the
/// result's log-Jacobian spread and folding over the fixed foreground. Metrics a result cannot
/// give (landmarks, endpoint error and Jacobian from a label map) are null, with the reason.
/// @throws InputError naming the file or option that is missing or does not fit
nlohmann::json evaluate_registration(const EvaluationRequest& request);

/// The evaluation as a table a person reads: one line per metric, one per label.
std::string evaluation_table(const nlohmann::json& evaluation);

} // namespace phantasm
