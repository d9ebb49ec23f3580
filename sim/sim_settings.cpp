#include "sim/sim_settings.hpp"

#include "sim/load_type.hpp"

#include <algorithm>

namespace phantasm {
namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

} // namespace

std::vector<OrganMotion> classify_organ_motion(const DeformationSettings& d, const OrganTable& organs) {
  std::vector<OrganMotion> motion(organs.size(), OrganMotion::rigid);
  if (d.mode == DeformationMode::none) return motion;
  for (std::size_t i = 0; i < organs.size(); ++i) {
    const std::string& name = organs[i].name;
    if (contains(d.fixed, name)) {
      motion[i] = OrganMotion::fixed;
      continue;
    }
    for (const auto& load : d.loads)
      if (load_type(load.kind).acts_on(load, name)) motion[i] = OrganMotion::simulated;
  }
  // A growing organ pushes on (or pulls) the tissue around it: the solid organs holding it are
  // simulated with it, up to a fixed one or a surface organ.
  for (const auto& load : d.loads) {
    if (!load_type(load.kind).changes_rest_volume) continue;
    // Atlas regions may lie in any solid organ: those that are not fixed are simulated.
    for (std::size_t i = 0; !load.regions.empty() && i < organs.size() && i < d.organs.size(); ++i)
      if (d.organs[i].solid && motion[i] != OrganMotion::fixed) motion[i] = OrganMotion::simulated;
    const int grown = organs.index_of(load.organ);
    if (grown < 0) continue;
    for (int j = organs[static_cast<std::size_t>(grown)].parent; j >= 0;
         j = organs[static_cast<std::size_t>(j)].parent) {
      const auto k = static_cast<std::size_t>(j);
      if (motion[k] == OrganMotion::fixed || (k < d.organs.size() && !d.organs[k].solid)) break;
      motion[k] = OrganMotion::simulated;
    }
  }
  return motion;
}

std::string growth_target(const LoadSettings& load) {
  if (load.regions.empty()) return load.organ;
  std::string names;
  for (const std::string& region : load.regions)
    names += (names.empty() ? "" : ", ") + region;
  return names + " (atlas " + load.atlas + ")";
}

const MaterialSettings* DeformationSettings::find_material(const std::string& material_name) const {
  for (const auto& m : materials) {
    if (m.name == material_name) return &m;
  }
  return nullptr;
}

const char* to_string(DeformationMode mode) {
  switch (mode) {
  case DeformationMode::none: return "none";
  case DeformationMode::quasi_static: return "quasi_static";
  case DeformationMode::dynamic: return "dynamic";
  }
  return "?";
}

const char* to_string(VolumeFormulation volume) {
  switch (volume) {
  case VolumeFormulation::tet: return "per_tet";
  case VolumeFormulation::vertex_star: return "vertex_stars";
  case VolumeFormulation::tet_group: return "tet_groups";
  case VolumeFormulation::tet_group_and_tet: return "tet_groups_and_tets";
  }
  return "?";
}

const char* to_string(ObstacleShape shape) {
  return shape == ObstacleShape::sphere ? "sphere" : "half_space";
}

const char* to_string(MotionProfile motion) {
  switch (motion) {
  case MotionProfile::constant: return "constant";
  case MotionProfile::ramp: return "ramp";
  case MotionProfile::sine: return "sine";
  }
  return "?";
}

} // namespace phantasm
