// Every setting of the stages' settings structs declared once (core/settings_declaration.hpp):
// name, type, unit, bounds, help and the cached results it shapes. The caches' keys, `phantasm
// info --settings` and the tests read these declarations; a member of a settings struct that is
// declared nowhere does not compile (settings_members()).
#pragma once

#include "core/settings_declaration.hpp"
#include "scene/scene.hpp"

#include <vector>

namespace phantasm {

/// The declared fields of a settings struct, in the order of its keys' texts. Declared for
/// GridSettings, ShapeSettings, OrganSettings, AnatomySettings, VoxelizationSettings,
/// TissueOverride, SequenceSettings, AcquisitionSettings, TissueRegionSettings, TextureSettings,
/// MriSettings, OutputSettings, MaterialSettings, SolverSettings, LoadSettings, ObstacleSettings,
/// CollisionSettings, OrganMechanics, HeadScaleSettings and DeformationSettings.
template <typename S>
const std::vector<SettingField<S>>& declared_settings();

/// The address of every data member of a settings struct, by structured binding: a member added
/// to the struct fails to compile here until it is declared (tests/scene/test_settings_declarations.cpp
/// compares these with the declared fields' members).
std::vector<const void*> settings_members(const GridSettings& s);
std::vector<const void*> settings_members(const ShapeSettings& s);
std::vector<const void*> settings_members(const OrganSettings& s);
std::vector<const void*> settings_members(const AnatomySettings& s);
std::vector<const void*> settings_members(const VoxelizationSettings& s);
std::vector<const void*> settings_members(const TissueOverride& s);
std::vector<const void*> settings_members(const SequenceSettings& s);
std::vector<const void*> settings_members(const AcquisitionSettings& s);
std::vector<const void*> settings_members(const TissueRegionSettings& s);
std::vector<const void*> settings_members(const TextureSettings& s);
std::vector<const void*> settings_members(const MriSettings& s);
std::vector<const void*> settings_members(const OutputSettings& s);
std::vector<const void*> settings_members(const MaterialSettings& s);
std::vector<const void*> settings_members(const SolverSettings& s);
std::vector<const void*> settings_members(const LoadSettings& s);
std::vector<const void*> settings_members(const ObstacleSettings& s);
std::vector<const void*> settings_members(const CollisionSettings& s);
std::vector<const void*> settings_members(const OrganMechanics& s);
std::vector<const void*> settings_members(const HeadScaleSettings& s);
std::vector<const void*> settings_members(const DeformationSettings& s);

/// One line per declared setting of a scene's stages: "section.name  type  unit  bounds  default:
/// value  shapes: caches  help", for `phantasm info --settings` and docs/scene-format.md's table.
std::vector<std::string> settings_table(const Scene& scene);

} // namespace phantasm
