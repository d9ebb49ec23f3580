// What fills the space an organ leaves when it moves inside a container that stays where it is
// (docs/volumes-and-images.md, "The gap"). Without it the space would belong to the container
// by nesting (bone where the brain sags away from the skull).
#pragma once

#include "core/organ_table.hpp"
#include "core/stage_report.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/tissue_volumes.hpp"
#include "voxelize/voxelize_settings.hpp"

#include <string>
#include <vector>

namespace phantasm {

/// The index of the gap tissue in the tissue list, -1 for air (no tissue: the gap is counted as
/// background).
/// @param gap_fill the resolved gap tissue (VoxelizationSettings::gap_fill)
/// @param tissues the tissues of the organs, in the voxelizer's order
/// @throws SettingError naming deformation.gap_tissue when it is neither air nor a tissue of the list
int gap_tissue_index(const std::string& gap_fill, const std::vector<std::string>& tissues);

/// The gaps of the deformed state, as organs for voxelize_tissues(): for each organ the solver
/// moved (a body, or embedded in one) whose container stays and is voxelized, its reference
/// level set at a depth between the container's and that of the organs the container holds
/// (organs sit at even depths, twice their nesting depth). A point inside the container, inside
/// the organ's reference shape and outside every deformed organ nested in the container is
/// space the organ left: the gap tissue fills it, label organs.size() + 1. What was filled goes
/// into `report`.
/// @param gap_fill the resolved gap tissue, "air" or a tissue name
/// @param tissue the gap tissue's index (gap_tissue_index())
/// @param organs the organ table
/// @param deformation how every organ moved (OrganDeformation::moved_by), in table order
/// @param reference the voxelized organs of the reference state (their level sets must outlive
///        the result)
std::vector<VoxelizedOrgan> gap_organs(const std::string& gap_fill, int tissue, const OrganTable& organs,
                                       const PhantomDeformation& deformation,
                                       const std::vector<VoxelizedOrgan>& reference, StageReport& report);

} // namespace phantasm
