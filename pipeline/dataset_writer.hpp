// Writing a complete simulation as the dataset: the files are listed first, then written in
// list order, provenance.json last.
#pragma once

#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "pipeline/simulation.hpp"
#include "scene/scene.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

struct RunSummary {
  std::vector<StageReport> stages;
  std::vector<std::filesystem::path> files; ///< written, relative to the dataset folder
};

/// Every stage's warnings, "[stage] message", in stage order.
std::vector<std::string> stage_warnings(const std::vector<StageReport>& stages);

/// Checks that the organ and tissue names of the scene give distinct, non-empty BIDS entity values
/// (bids_entity_value: "ventricle_left" and "ventricleLeft" would name the same files).
/// @throws InputError naming the names that clash
void check_dataset_names(const Scene& scene);

/// Writes a complete simulation (every stage run) as the dataset (docs/architecture.md) into `output`,
/// provenance.json last. The folder must have been prepared (prepare_output_folder). The files
/// are first listed (path and how to make its bytes), then written in list order: the progress
/// bar counts the list, and what is written is exactly what was listed.
/// @throws Cancelled when cancellation was requested; files already written stay complete
RunSummary write_dataset(const Scene& scene, const Simulation& simulation,
                         const std::filesystem::path& output, Reporter& reporter);

} // namespace phantasm
