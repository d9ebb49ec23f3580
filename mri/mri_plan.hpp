// The MR stage's plan: the images it will make for a scene, the tissue values used and the
// acquisition effects asked for.
#pragma once

#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "mri/mri_settings.hpp"

namespace phantasm {

/// What the MR stage will make: one image per sequence and state, the tissue values used for the
/// organs' tissues, and the acquisition effects the settings ask for (k-space, bias, coils, noise).
/// With k-space on a grid whose size along an axis has a prime factor above 13, it says so and
/// names the next sizes without one (largest_prime_factor, core/grid.hpp): FFTW transforms those
/// several times faster per voxel.
StageReport plan_mri(const MriSettings& settings, const OrganTable& organs, const GridSettings& grid);

} // namespace phantasm
