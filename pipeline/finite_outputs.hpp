// The last check before a dataset is written: every array it would hold is finite.
#pragma once

#include "pipeline/simulation.hpp"

#include <filesystem>

namespace phantasm {

/// Refuses a run whose results hold NaN or infinity anywhere the dataset writes them (the MR
/// images and parameter maps, the displacement fields and their Jacobians, the landmarks, the
/// simulated bodies' vertices): the first such value is named by its array (the sequence and
/// state of an image), its voxel and the tissue there.
/// @param scene_file the scene the run read, named first in the message
/// @throws InputError naming the value; nothing is written then
void require_finite_outputs(const Simulation& simulation, const std::filesystem::path& scene_file = {});

} // namespace phantasm
