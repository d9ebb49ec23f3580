// Scoring a folder of registration results against a Learn2Reg task's ground truth
// (`phantasm eval TASK --results DIR`), with a warning for a field that looks read the wrong way.
#pragma once

#include "evaluation/field_conventions.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// A likely misreading of a field: what the mistake is, and the endpoint errors (voxels, mean
/// over the exact mask where the truth moves) of the result as read and corrected for it.
struct Misreading {
  std::string mistake;
  double error_as_read_voxels = 0.0, error_if_so_voxels = 0.0;
};

/// Tries the usual ways a field is read wrong (inverse direction or fixed and moving swapped,
/// mm for voxels and voxels for mm, transposed or reversed components, an array flipped along an
/// axis, positions for displacements, a constant offset of whole voxels) and returns the one that
/// brings the result closest to the truth when it explains most of the error; none when the
/// result is close to the truth as read, or no mistake explains it.
/// @param mask the voxels where the truth is exact
std::vector<Misreading> likely_misreadings(const DisplacementField& result, const DisplacementField& truth,
                                           const std::vector<bool>& mask);

/// What to score.
struct TaskScoreRequest {
  std::filesystem::path task;    ///< the folder `phantasm task` made
  std::filesystem::path truth;   ///< its ground-truth folder
  std::filesystem::path results; ///< one disp_<fixed>_<moving>.nii.gz per pair
  FieldConvention convention = FieldConvention::learn2reg;
};

/// Scores every pair: Dice and HD95 per label, TRE on the keypoints, endpoint error in the exact
/// mask, the non-diffeomorphic volume, the central-difference folding fraction and the spread of
/// log det J, with a summary over pairs and the warnings. Every result is read and checked before
/// anything is scored.
/// @throws InputError naming the file: missing or extra results, a result of another shape or
/// datatype, NaN or infinite values, a ground truth of another task
nlohmann::json score_task(const TaskScoreRequest& request);

/// TRE on dense landmarks as JSON: the summary over every point (count, mean, sd, p95, max) and
/// "by_structure", one summary per organ (with its name) in the order the organs first appear.
/// @param organs per point, its organ
/// @param tre per point, its TRE (mm)
nlohmann::json dense_tre_json(const std::vector<std::string>& organs, const std::vector<double>& tre);

/// One line per pair (CSV with a header).
std::string task_scores_csv(const nlohmann::json& scores);
/// The scores as a table a person reads.
std::string task_scores_table(const nlohmann::json& scores);

} // namespace phantasm
