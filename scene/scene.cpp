#include "scene/scene.hpp"

#include "mri/sequence_type.hpp"

namespace phantasm {

const OrganSettings* Scene::find_organ(const std::string& organ_name) const {
  for (const auto& o : anatomy.organs) {
    if (o.name == organ_name) return &o;
  }
  return nullptr;
}

SourceLocation Scene::location_of(const std::string& key_path) const {
  // Fall back to the nearest enclosing key that was seen.
  std::string path = key_path;
  while (!path.empty()) {
    const auto found = locations.find(path);
    if (found != locations.end()) return found->second;
    const auto cut = path.find_last_of(".[");
    if (cut == std::string::npos) break;
    path.resize(cut);
  }
  return SourceLocation{file.string(), 0, 0};
}

std::string default_gap_tissue(const DeformationSettings& deformation, const OrganTable& organs) {
  const std::vector<OrganMotion> motion = classify_organ_motion(deformation, organs);
  std::vector<bool> moves(organs.size(), false);
  for (std::size_t i = 0; i < organs.size(); ++i) {
    // The bound guards against a cycle, which the scene's validation rejects.
    std::size_t steps = 0;
    for (int j = static_cast<int>(i); j >= 0 && steps <= organs.size();
         j = organs[static_cast<std::size_t>(j)].parent, ++steps)
      if (motion[static_cast<std::size_t>(j)] == OrganMotion::simulated) moves[i] = true;
  }
  for (std::size_t i = 0; i < organs.size(); ++i) {
    const int container = organs[i].parent;
    if (!moves[i] || container < 0 || moves[static_cast<std::size_t>(container)]) continue;
    if (organs[static_cast<std::size_t>(container)].tissue == "csf") return "csf";
    for (const OrganEntry& sibling : organs)
      if (sibling.parent == container && sibling.tissue == "csf") return "csf";
  }
  return "air";
}

void resolve_stage_settings(Scene& scene) {
  const std::vector<OrganSettings>& organs = scene.anatomy.organs;
  scene.organs = organ_table(scene.anatomy);
  scene.anatomy.seed = scene.seed;

  DeformationSettings& deformation = scene.deformation;
  deformation.organs.clear();
  for (const OrganSettings& organ : organs)
    deformation.organs.push_back(
        {organ.material, organ.solid, organ.thickness_mm, organ.enclosed_volume_tolerance});

  VoxelizationSettings& voxelization = scene.voxelization;
  const OutputSettings& outputs = scene.outputs;
  voxelization.deformed = deformation.mode != DeformationMode::none;
  voxelization.keep_level_sets = outputs.vdb;
  voxelization.labels = outputs.labels;
  voxelization.fractions = outputs.fractions || outputs.images;
  voxelization.displacement_fields = outputs.displacement_fields;
  voxelization.jacobian = outputs.jacobian;
  voxelization.landmarks = outputs.landmarks;
  voxelization.dense_landmarks = outputs.landmarks ? outputs.dense_landmarks : 0;
  voxelization.gap_fill = voxelization.gap_tissue.empty() ? default_gap_tissue(deformation, scene.organs)
                                                          : voxelization.gap_tissue;
  voxelization.organ_bounds_mm.clear();
  for (const OrganSettings& organ : organs)
    voxelization.organ_bounds_mm.push_back(analytic_shape_bounds(organ.shape));

  MriSettings& mri = scene.mri;
  mri.seed = scene.seed;
  mri.images = outputs.images;
  mri.parameter_maps = outputs.parameter_maps;
  for (SequenceSettings& sequence : mri.sequences) {
    // Values that depend on others, by the sequence's member (bSSFP: TE = TR / 2 unless given).
    const SequenceType& type = sequence_type(sequence.kind);
    if (type.resolve) type.resolve(sequence);
  }
}

} // namespace phantasm
