#pragma once

#include "anatomy/phantom.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "mri/synthesize_images.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <filesystem>
#include <optional>
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

/// What a run computes, before anything is written.
struct Simulation {
  std::vector<StageReport> stages; ///< plans, completed by the stages that ran
  Phantom phantom;                 ///< the reference anatomy
  std::optional<PhantomDeformation> deformation;
  std::optional<Phantom> deformed;
  VoxelizedPhantom volumes;
  MrImages images; ///< refers to the scene's sequences: keep the scene alive
};

/// The last stage simulate() runs.
enum class SimulationStage { anatomy, deformation, voxelization, mri };

/// Runs a scene's stages in data-flow order up to `until`, writing nothing.
Simulation simulate(const Scene& scene, Reporter& reporter, SimulationStage until = SimulationStage::mri);

/// Writes a complete simulation (every stage run) as the dataset of DESIGN.md into `output`,
/// provenance.json last. The folder must have been prepared (prepare_output_folder).
RunSummary write_dataset(const Scene& scene, const Simulation& simulation,
                         const std::filesystem::path& output, Reporter& reporter);

/// Runs a scene through every stage and writes the dataset (DESIGN.md, output layout).
/// provenance.json is written last: its presence marks a complete subject.
/// @throws InputError for an output folder that may not be written into
/// @throws Cancelled when cancellation was requested; files already written stay complete
RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter);

} // namespace phantasm
