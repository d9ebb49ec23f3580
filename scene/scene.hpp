// The scene: every setting of a run (grid, materials, tissues, anatomy, deformation,
// voxelization, sequences, acquisition, outputs) as checked values, and loading it from YAML.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "core/grid.hpp"
#include "core/organ_table.hpp"
#include "mri/mri_settings.hpp"
#include "scene/diagnostic.hpp"
#include "sim/sim_settings.hpp"
#include "voxelize/voxelize_settings.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A set of outputs named at once (outputs.profile): full writes every output the switches ask
/// for; benchmark leaves out what a registration benchmark does not read (organ meshes, OpenVDB
/// grids, previews, tissue fractions, parameter maps) unless the scene asks for them by name.
enum class OutputProfile { full, benchmark };

struct OutputSettings {
  std::string subject = "01";
  OutputProfile profile = OutputProfile::full;
  bool images = true;
  bool labels = true;
  bool fractions = true;
  bool displacement_fields = true;
  bool jacobian = true;
  bool landmarks = true;
  int dense_landmarks = 300; ///< per closed organ, with the landmarks; 0: none
  bool meshes = true;
  bool vdb = false;
  bool previews = true;
  bool parameter_maps = true; ///< PD, T1, T2, T2* maps of each state
};

/// A parsed and validated scene file: the settings of every stage, each resolved (defaults,
/// what a stage reads of other sections), and where each key was written. Stages take their own
/// settings and the organ table; only the pipeline sees the whole scene.
struct Scene {
  std::filesystem::path file; ///< the scene file as given
  std::string sha256;         ///< hash of the file's bytes
  std::string source_text;    ///< the file's bytes, kept for the copy in the dataset
  std::string name;
  std::uint64_t seed = 0;
  GridSettings grid;
  AnatomySettings anatomy;
  DeformationSettings deformation; ///< with the materials section
  VoxelizationSettings voxelization;
  MriSettings mri; ///< field strength, tissues, sequences, acquisition
  OutputSettings outputs;
  OrganTable organs; ///< names, tissues and nesting of anatomy.organs

  /// Where each key was found, by key path ("grid.voxel_size_mm"), for later messages.
  std::map<std::string, SourceLocation> locations;

  const OrganSettings* find_organ(const std::string& name) const;
  /// The location of a key path, or of the file when the path is unknown.
  SourceLocation location_of(const std::string& key_path) const;
};

/// Fills what each stage reads of other sections and the defaults that depend on other values:
/// the organ table, the seed of anatomy and mri, the organs' mechanics for the deformation, the
/// outputs voxelize and mri make, the organs' nominal bounds, the gap tissue (default_gap_tissue()
/// unless given), and bSSFP echo times (TR / 2 unless given). parse_scene() calls it; call it again after
/// changing a parsed scene's values.
void resolve_stage_settings(Scene& scene);

/// What fills the gaps of a scene when deformation.gap_tissue is not given (docs/scene-format.md):
/// "csf" when an organ of tissue csf is a moved organ whose container stays, that container, or
/// another organ inside that container (the fluid the container holds flows into the space the
/// organ leaves); else "air" (nothing fills it: no signal). An organ moves when it or an organ
/// containing it is simulated (classify_organ_motion()).
/// @param deformation the deformation settings (mode, fixed organs, loads)
/// @param organs the organ table
std::string default_gap_tissue(const DeformationSettings& deformation, const OrganTable& organs);

/// The result of reading a scene: a scene when there was no problem, else every problem found.
struct SceneLoadResult {
  std::optional<Scene> scene;
  std::vector<Diagnostic> problems;
};

/// The most a scene or sweep file may hold: a scene is a few kB, and a device such as /dev/zero
/// or an endless pipe would otherwise be read until memory runs out.
inline constexpr std::size_t k_max_scene_file_bytes = std::size_t{64} << 20;

/// Reads the text of a scene or sweep file.
/// @param text the file's bytes, when it could be read
/// @return "" when read, or what was found instead, to follow "expected a scene file, ": "found
/// no such file", "found a folder", "found a device node", "found a file that cannot be opened",
/// "found more than 64 MB"
std::string read_scene_text(const std::filesystem::path& file, std::string& text);

/// Reads, parses and validates a scene file (docs/scene-format.md). Never throws for bad input.
SceneLoadResult load_scene(const std::filesystem::path& file);

/// Parses scene text; `file` names it in messages and anchors relative paths.
SceneLoadResult parse_scene(const std::string& text, const std::filesystem::path& file);

} // namespace phantasm
