// The parsers of the scene file's sections, each filling its settings from a checked YAML map.
// Internal to the scene target.
#pragma once

// The parsers of each scene section. Internal to the scene target.

#include "scene/scene.hpp"
#include "scene/yaml_checker.hpp"

namespace phantasm::scene_detail {

void parse_grid(CheckedMap& map, GridSettings& grid);
void parse_materials(CheckedMap& map, std::vector<MaterialSettings>& materials);
void parse_tissues(CheckedMap& map, std::vector<TissueOverride>& tissues);
void parse_anatomy(CheckedMap& map, const std::filesystem::path& scene_folder, AnatomySettings& anatomy);
/// The deformation section; its gap_tissue key goes to the voxelization, which fills the gap.
void parse_deformation(CheckedMap& map, DeformationSettings& deformation, VoxelizationSettings& voxelization);
void parse_voxelization(CheckedMap& map, VoxelizationSettings& voxelization);
void parse_sequences(YamlContext& context, const YAML::Node& node, std::vector<SequenceSettings>& sequences);
void parse_acquisition(CheckedMap& map, AcquisitionSettings& acquisition);
void parse_outputs(CheckedMap& map, OutputSettings& outputs);
void parse_tissue_regions(YamlContext& context, const YAML::Node& node,
                          std::vector<TissueRegionSettings>& regions);
void parse_texture(CheckedMap& map, const std::filesystem::path& scene_folder, TextureSettings& texture);

/// Checks that need more than one section: references between sections, tissue values the
/// sequences need, consistent timings. Runs only on a scene whose sections parsed cleanly.
void check_consistency(YamlContext& context, const Scene& scene);

/// Reports a problem at `at` unless `value` obeys the name rule of core/safe_name.hpp (names
/// that reach file names: organs, tissues, materials, the scene's name).
/// @return true when the name is accepted
bool check_name(YamlContext& context, const YAML::Node& at, const std::string& key_path,
                const std::string& value);

/// True for a BIDS label: letters and digits only.
bool is_bids_label(const std::string& text);

} // namespace phantasm::scene_detail
