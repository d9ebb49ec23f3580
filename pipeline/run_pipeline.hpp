#pragma once

#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "scene/scene.hpp"

#include <filesystem>
#include <vector>

namespace phantasm {

struct RunOptions {
  std::filesystem::path output; ///< the dataset folder
  bool force = false;           ///< write into a folder that already holds files
};

struct RunSummary {
  std::vector<StageReport> stages;
  std::vector<std::filesystem::path> files; ///< written, relative to the dataset folder
};

/// Each stage's plan for a scene, in data-flow order (anatomy, sim, voxelize, mri).
std::vector<StageReport> plan_stages(const Scene& scene);

/// Runs a scene through every stage and writes the dataset (DESIGN.md, output layout).
/// provenance.json is written last: its presence marks a complete subject.
/// @throws InputError for an output folder that may not be written into
/// @throws Cancelled when cancellation was requested; files already written stay complete
RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter);

} // namespace phantasm
