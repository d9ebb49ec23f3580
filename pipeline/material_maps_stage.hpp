// Tissue regions and texture attached to a voxelized phantom: the reference state's made in
// reference space from an atlas or a scan, the deformed state's looked up through the exact map
// (voxelize/material_maps.hpp; docs/volumes-and-images.md, "Tissue regions and texture").
#pragma once

#include "core/stage_report.hpp"
#include "scene/scene.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <map>
#include <string>
#include <vector>

namespace phantasm {

struct AtlasLabelVolume; // io/shape_files.hpp: the stage's callers hold the atlases, io stays private

/// The dseg labels of the scene's tissue regions, in scene order: after the organs and the gap.
std::int32_t first_region_label(const Scene& scene);

/// Applies the scene's tissue regions (their tissues join the phantom's list) and texture to both
/// states of `volumes`, recording what was done in `report`.
/// @param atlases the label volumes the organs' shapes were made from, by atlas name
/// @throws SettingError for a region label the atlas lacks (tissue_regions[i].label)
/// @throws InputError for a texture scan that cannot be read or does not cover the textured tissue
void attach_material_maps(const Scene& scene, const std::map<std::string, AtlasLabelVolume>& atlases,
                          VoxelizedPhantom& volumes, StageReport& report);

/// What the material maps add to the reference state's cache keys (empty without regions or texture).
std::string material_maps_key_text(const Scene& scene);

} // namespace phantasm
