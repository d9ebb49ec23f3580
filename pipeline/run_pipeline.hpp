// Running a scene through the stages in data-flow order (anatomy, sim, voxelize, mri): their
// plans, the simulation without writing, and a whole run that writes the dataset.
#pragma once

#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "geometry/shape_data.hpp"
#include "pipeline/dataset_writer.hpp"
#include "pipeline/simulation.hpp"
#include "scene/scene.hpp"

#include <filesystem>
#include <map>
#include <stdexcept>
#include <vector>

namespace phantasm {

struct RunOptions {
  std::filesystem::path output; ///< the dataset folder
  bool force = false;           ///< write into a folder that already holds files
  /// a result the run cannot vouch for (an unconverged solve, inverted tets, a non-positive
  /// Jacobian inside an exact mask) is an error: StrictError before anything is written
  bool strict = false;
  /// the caller made the output folder for this run (to lock it): a run that fails on its input
  /// removes it again when it is still empty, as one that made it itself
  bool output_created = false;
  /// the anatomy cache folder (pipeline/anatomy_cache.hpp), which also holds the reference cache
  /// (pipeline/reference_cache.hpp): runs with the same anatomy build it once, and with the same
  /// grid and voxelization too voxelize the reference state once; empty: no cache
  std::filesystem::path anatomy_cache;
};

/// A run with --strict whose stages warned: nothing of the subject was written.
class StrictError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// Each stage's plan for a scene, in data-flow order (anatomy, sim, voxelize, mri).
std::vector<StageReport> plan_stages(const Scene& scene);

/// The files a scene's organs are made of (meshes, label volumes), by organ name, as a run reads
/// them: atlas labels are derived once, and what was derived, from which inputs, with the
/// sources to cite, goes to `report` and the reporter.
std::map<std::string, ShapeData> read_scene_shape_files(const Scene& scene, StageReport& report,
                                                        Reporter& reporter);

/// The last stage simulate() runs.
enum class SimulationStage { anatomy, deformation, voxelization, mri };

/// Runs a scene's stages in data-flow order up to `until`, writing nothing but the caches.
/// @param anatomy_cache the folder of the anatomy and reference caches (pipeline/anatomy_cache.hpp,
///        pipeline/reference_cache.hpp); empty: none
Simulation simulate(const Scene& scene, Reporter& reporter, SimulationStage until = SimulationStage::mri,
                    const std::filesystem::path& anatomy_cache = {});

/// Runs a scene through every stage and writes the dataset (docs/architecture.md, dataset layout).
/// provenance.json is written last: its presence marks a complete subject.
/// @throws InputError for an output folder that may not be written into
/// @throws StrictError with options.strict when a stage warned (nothing of the subject written)
/// @throws Cancelled when cancellation was requested; files already written stay complete
RunSummary run_scene(const Scene& scene, const RunOptions& options, Reporter& reporter);

} // namespace phantasm
