// Simulation: every stage's result of a run before anything is written (types only), the data
// passed from the stages to the dataset writer.
#pragma once

#include "anatomy/organ.hpp"
#include "core/stage_report.hpp"
#include "mri/mr_images.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// Where a run's reference state and its images are kept across runs (docs/batch.md): the
/// reference session's files follow from them, so the writer keeps their bytes beside them.
struct ReferenceEntries {
  std::filesystem::path folder; ///< the cache folder; empty: no cache
  std::string state_key;        ///< reference_cache_key(): labels, fractions, meshes
  std::string images_key;       ///< reference_images_key(): images, previews, maps; empty: none
};

/// What a run computes, before anything is written: every stage's result (types only, so that
/// the dataset writer includes no stage).
struct Simulation {
  std::vector<StageReport> stages; ///< plans, completed by the stages that ran
  Phantom phantom;                 ///< the reference anatomy
  std::optional<PhantomDeformation> deformation;
  std::optional<Phantom> deformed;
  VoxelizedPhantom volumes;
  MrImages images; ///< refers to the scene's sequences: keep the scene alive
  ReferenceEntries reference_entries;
  std::vector<StageTiming> timings; ///< each stage that ran, in order (the report's stage times)
};

} // namespace phantasm
