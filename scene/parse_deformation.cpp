#include "scene/parse_sections.hpp"
#include "sim/solver_type.hpp"

namespace phantasm::scene_detail {
namespace {

void parse_solver(CheckedMap& map, SolverSettings& solver) {
  std::string method;
  if (map.choice("method", method, solver_type_names())) solver.method = find_solver_type(method)->method;
  map.integer("max_iterations", solver.max_iterations, 1, 1000000);
  map.number("relative_energy_tolerance", solver.relative_energy_tolerance, between(0.0, 1.0, ""));
  map.number("position_tolerance_mm", solver.position_tolerance_mm, non_negative("mm"));
  map.number("relative_residual_tolerance", solver.relative_residual_tolerance, between(0.0, 1.0, ""));
  map.integer("threads", solver.threads, 0, 1024);
}

void parse_motion(CheckedMap& map, MotionProfile& profile, double& period_s) {
  std::string motion;
  if (map.choice("motion", motion, {"constant", "ramp", "sine"})) {
    profile = motion == "ramp"   ? MotionProfile::ramp
              : motion == "sine" ? MotionProfile::sine
                                 : MotionProfile::constant;
  }
  map.number("period_s", period_s, positive("s"));
}

void parse_obstacle(CheckedMap& map, ObstacleSettings& obstacle) {
  std::string shape;
  if (!map.choice("type", shape, {"half_space", "sphere"}, true)) {
    map.accept_remaining_keys();
    return;
  }
  const NumberRule coordinate{-1e5, 1e5, false, false, "mm"};
  if (shape == "half_space") {
    obstacle.shape = ObstacleShape::half_space;
    map.vec3("point_mm", obstacle.point_mm, coordinate, true);
    if (map.vec3("normal", obstacle.normal, NumberRule{-1e6, 1e6, false, false, ""}, true)) {
      if (!(obstacle.normal.norm() > 1e-12)) {
        map.context().problem(
            map.get("normal"), map.child_path("normal"),
            "expected a non-zero normal (pointing out of the obstacle, towards the tissue), "
            "found [0, 0, 0]");
      } else {
        obstacle.normal.normalize();
      }
    }
  } else {
    obstacle.shape = ObstacleShape::sphere;
    map.vec3("center_mm", obstacle.point_mm, coordinate, true);
    map.number("radius_mm", obstacle.radius_mm, positive("mm"), true);
  }
  map.vec3("displacement_mm", obstacle.displacement_mm, NumberRule{-1e3, 1e3, false, false, "mm"});
  parse_motion(map, obstacle.motion, obstacle.period_s);
}

/// A list of mappings under `key`, each read by `parse` into a new element of `out`.
template <typename Settings, typename Parse>
void parse_list(CheckedMap& map, const std::string& key, const char* what, std::vector<Settings>& out,
                Parse&& parse) {
  const YAML::Node list = map.get(key);
  if (!list.IsDefined()) return;
  const std::string path = map.child_path(key);
  if (!list.IsSequence()) {
    map.context().problem(list, path,
                          std::string("expected a list of ") + what + ", found " + describe(list));
    return;
  }
  for (std::size_t i = 0; i < list.size(); ++i) {
    CheckedMap entry(map.context(), list[i], path + "[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    Settings settings;
    parse(entry, settings);
    out.push_back(settings);
  }
}

/// A growth load's regions: `region` (a name or a list of names of regions or groups) and the
/// `atlas` they are of; the names are resolved when the atlas is read.
void parse_growth_regions(CheckedMap& map, LoadSettings& load) {
  map.choice("atlas", load.atlas, {"aal"}, true);
  const YAML::Node region = map.get("region");
  if (!region.IsDefined()) {
    map.missing("region", "a region of the atlas or a list of them (Hippocampus_L, [Hippocampus, cortex])");
  } else if (region.IsSequence()) {
    if (map.string_list("region", load.regions) && load.regions.empty())
      map.context().problem(region, map.child_path("region"), "expected at least one region, found []");
  } else {
    std::string name;
    if (map.string("region", name)) load.regions = {name};
  }
}

void parse_load(CheckedMap& map, LoadSettings& load) {
  std::string kind;
  if (!map.choice("type", kind, {"gravity", "displacement", "growth"}, true)) {
    map.accept_remaining_keys();
    return;
  }
  const NumberRule coordinate{-1e5, 1e5, false, false, "mm"};
  if (kind == "gravity") {
    load.kind = LoadKind::gravity;
    map.vec3("acceleration_m_s2", load.acceleration_m_s2, NumberRule{-1e4, 1e4, false, false, "m/s^2"}, true);
    map.string_list("organs", load.organs);
  } else if (kind == "growth") {
    // The rest volume of the organ's tets, or of the tets in atlas regions, changes by
    // volume_change; -1 would leave no tissue.
    load.kind = LoadKind::growth;
    if (map.has("region") || map.has("atlas")) {
      parse_growth_regions(map, load);
      if (map.has("organ"))
        map.context().problem(map.get("organ"), map.child_path("organ"),
                              "expected organ or region, not both, found both");
    } else {
      map.string("organ", load.organ, true);
    }
    map.number("volume_change", load.volume_change, NumberRule{-1.0, 10.0, true, false, ""}, true);
    return;
  } else {
    load.kind = LoadKind::displacement;
    map.string("organ", load.organ, true);
    // A turn alone (a clamp twisting a bar's end) needs no displacement.
    const bool turned = map.has("rotation");
    map.vec3("displacement_mm", load.displacement_mm, NumberRule{-1e3, 1e3, false, false, "mm"}, !turned);
    if (turned) {
      CheckedMap rotation(map.context(), map.get("rotation"), map.child_path("rotation"));
      if (rotation.valid()) {
        rotation.number("angle_deg", load.rotation_deg, between(-360.0, 360.0, "degrees"), true);
        rotation.vec3("center_mm", load.rotation_center_mm, coordinate, true);
        if (rotation.vec3("axis", load.rotation_axis, NumberRule{-1e6, 1e6, false, false, ""}, true)) {
          if (!(load.rotation_axis.norm() > 1e-12)) {
            map.context().problem(rotation.get("axis"), rotation.child_path("axis"),
                                  "expected a non-zero axis, found [0, 0, 0]");
          } else {
            load.rotation_axis.normalize();
          }
        }
      }
    }
    if (map.has("region")) {
      CheckedMap region(map.context(), map.get("region"), map.child_path("region"));
      if (region.valid()) {
        region.vec3("center_mm", load.region_center_mm, coordinate, true);
        region.number("radius_mm", load.region_radius_mm, positive("mm"), true);
      }
    } else {
      map.missing("region", "a mapping with center_mm and radius_mm (the part of the surface moved)");
    }
  }
  parse_motion(map, load.motion, load.period_s);
}

} // namespace

void parse_deformation(CheckedMap& map, DeformationSettings& deformation,
                       VoxelizationSettings& voxelization) {
  std::string mode;
  if (map.choice("mode", mode, {"none", "quasi_static", "dynamic"}, true)) {
    deformation.mode = mode == "quasi_static" ? DeformationMode::quasi_static
                       : mode == "dynamic"    ? DeformationMode::dynamic
                                              : DeformationMode::none;
  }
  if (map.has("solver")) {
    CheckedMap solver(map.context(), map.get("solver"), map.child_path("solver"));
    if (solver.valid()) parse_solver(solver, deformation.solver);
  }
  map.number("time_step_s", deformation.time_step_s, between(1e-6, 10.0, "s"));
  map.integer("frames", deformation.frames, 1, 100000);
  map.string_list("fixed", deformation.fixed);
  map.integer("load_steps", deformation.load_steps, 1, 10000);
  std::string volume;
  if (map.choice("volume", volume, {"per_tet", "tet_groups", "tet_groups_and_tets", "vertex_stars"})) {
    deformation.volume = volume == "tet_groups"            ? VolumeFormulation::tet_group
                         : volume == "tet_groups_and_tets" ? VolumeFormulation::tet_group_and_tet
                         : volume == "vertex_stars"        ? VolumeFormulation::vertex_star
                                                           : VolumeFormulation::tet;
  }
  map.string("gap_tissue", voxelization.gap_tissue);
  parse_list(map, "loads", "loads", deformation.loads, parse_load);
  parse_list(map, "obstacles", "obstacles", deformation.obstacles, parse_obstacle);
  parse_list(
      map, "collisions", "collisions", deformation.collisions, [](CheckedMap& entry, CollisionSettings& c) {
        if (entry.string_list("organs", c.organs, true) && c.organs.size() != 2) {
          entry.context().problem(entry.get("organs"), entry.child_path("organs"),
                                  "expected two organ names, found " + std::to_string(c.organs.size()));
        }
      });
}

} // namespace phantasm::scene_detail
