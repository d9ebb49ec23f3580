// StageReport: what a pipeline stage modelled, what it skipped and the accuracy it achieved,
// from each stage's plan and run into the run log and provenance.json.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace phantasm {

/// What one pipeline stage modelled, what it skipped because the scene did not need it, and the
/// accuracy it achieved. Collected into the run log and provenance.json.
struct StageReport {
  std::string stage;                      ///< "anatomy", "sim", "voxelize", "mri"
  std::string status = "planned";         ///< "planned", "done" or "skipped"
  std::vector<std::string> modelled;      ///< one line per thing modelled, with why
  std::vector<std::string> skipped;       ///< one line per thing left out, with why
  std::map<std::string, double> accuracy; ///< achieved accuracy figures, named with their unit
  /// results the stage could not vouch for (an unconverged solve, inverted elements, a
  /// non-positive Jacobian where the ground truth is marked exact); `--strict` makes them errors
  std::vector<std::string> warnings;
};

/// How long one stage of a run took ("anatomy", "deformation", "voxelization", "mri", "writing":
/// the cost estimate's names), set against the estimate in the subject's report.
struct StageTiming {
  std::string stage;
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0; ///< the process's processor time, every thread summed
};

} // namespace phantasm
