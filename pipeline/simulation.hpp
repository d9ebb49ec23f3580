// Simulation: every stage's result of a run before anything is written (types only), the data
// passed from the stages to the dataset writer.
#pragma once

#include "anatomy/organ.hpp"
#include "core/stage_report.hpp"
#include "mri/mr_images.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <optional>
#include <vector>

namespace phantasm {

/// What a run computes, before anything is written: every stage's result (types only, so that
/// the dataset writer includes no stage).
struct Simulation {
  std::vector<StageReport> stages; ///< plans, completed by the stages that ran
  Phantom phantom;                 ///< the reference anatomy
  std::optional<PhantomDeformation> deformation;
  std::optional<Phantom> deformed;
  VoxelizedPhantom volumes;
  MrImages images; ///< refers to the scene's sequences: keep the scene alive
};

} // namespace phantasm
