#include "scene/parse_sections.hpp"
#include "sim/load_type.hpp"
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

/// `key`: how a load or an obstacle moves in a dynamic scene (constant, ramp or sine).
void parse_motion_profile(CheckedMap& map, const std::string& key, MotionProfile& profile, bool required) {
  std::string motion;
  if (map.choice(key, motion, {"constant", "ramp", "sine"}, required)) {
    profile = motion == "ramp"   ? MotionProfile::ramp
              : motion == "sine" ? MotionProfile::sine
                                 : MotionProfile::constant;
  }
}

void parse_motion(CheckedMap& map, MotionProfile& profile, double& period_s) {
  parse_motion_profile(map, "motion", profile, false);
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

/// A load parameter's range for messages.
NumberRule rule_of(const LoadParameter& p) {
  return NumberRule{p.min, p.max, p.min_exclusive, p.max_exclusive, p.unit};
}

/// Whether the map has any of `keys` (each then known to it).
bool has_any(CheckedMap& map, const std::vector<std::string>& keys) {
  bool any = false;
  for (const std::string& key : keys)
    any = map.has(key) || any;
  return any;
}

/// Kind::name_or_names: one name or a non-empty list of them.
void parse_name_or_names(CheckedMap& map, const std::string& key, const LoadParameter& p, bool required,
                         LoadSettings& load) {
  const YAML::Node node = map.get(key);
  std::vector<std::string>& names = load.*p.names;
  if (!node.IsDefined()) {
    if (required) map.missing(key, p.expected);
  } else if (node.IsSequence()) {
    if (map.string_list(key, names) && names.empty())
      map.context().problem(node, map.child_path(key), "expected at least one " + key + ", found []");
  } else {
    std::string name;
    if (map.string(key, name)) names = {name};
  }
}

/// Kind::vector3 with `unit_vector`: three numbers, not all zero, then normalized.
void parse_direction(CheckedMap& map, const std::string& key, const LoadParameter& p, bool required,
                     LoadSettings& load) {
  Eigen::Vector3d& direction = load.*p.vector;
  if (!map.vec3(key, direction, rule_of(p), required)) return;
  if (!(direction.norm() > 1e-12)) {
    map.context().problem(map.get(key), map.child_path(key),
                          "expected a non-zero " + key + ", found [0, 0, 0]");
  } else {
    direction.normalize();
  }
}

/// The parameters [first, last) of a load, read from `map` (their keys relative to `prefix`, the
/// path of the mapping they are in: "rotation." or empty).
void parse_load_parameters(CheckedMap& map, const std::vector<LoadParameter>& parameters, std::size_t first,
                           std::size_t last, const std::string& prefix, LoadSettings& load);

/// A Kind::mapping parameter at `index` and the parameters of its keys after it.
/// @return the index after its keys
std::size_t parse_mapping(CheckedMap& map, const std::vector<LoadParameter>& parameters, std::size_t index,
                          const std::string& prefix, bool required, LoadSettings& load) {
  const LoadParameter& p = parameters[index];
  const std::string path = prefix + p.key + ".";
  std::size_t end = index + 1;
  while (end < parameters.size() && std::string(parameters[end].key).rfind(path, 0) == 0)
    ++end;
  const std::string key = p.key + prefix.size();
  if (map.has(key)) {
    CheckedMap inner(map.context(), map.get(key), map.child_path(key));
    if (inner.valid()) parse_load_parameters(inner, parameters, index + 1, end, path, load);
  } else if (required) {
    map.missing(key, p.expected);
  }
  return end;
}

void parse_load_parameters(CheckedMap& map, const std::vector<LoadParameter>& parameters, std::size_t first,
                           std::size_t last, const std::string& prefix, LoadSettings& load) {
  for (std::size_t i = first; i < last;) {
    const LoadParameter& p = parameters[i];
    const std::string key = p.key + prefix.size(); // its key in this mapping
    if (!p.excluded_by.empty() && has_any(map, p.excluded_by)) {
      if (map.has(key))
        map.context().problem(map.get(key), map.child_path(key),
                              "expected " + key + " or " + p.excluded_by.front() + ", not both, found both");
      ++i;
      continue;
    }
    const bool required = p.required && !(p.unless != nullptr && map.has(p.unless)) &&
                          (p.required_with.empty() || has_any(map, p.required_with));
    switch (p.kind) {
    case LoadParameter::Kind::number: map.number(key, load.*p.number, rule_of(p), required); break;
    case LoadParameter::Kind::vector3:
      if (p.unit_vector)
        parse_direction(map, key, p, required, load);
      else
        map.vec3(key, load.*p.vector, rule_of(p), required);
      break;
    case LoadParameter::Kind::organ: map.string(key, load.*p.text, required); break;
    case LoadParameter::Kind::organs: map.string_list(key, load.*p.names, required); break;
    case LoadParameter::Kind::name_or_names: parse_name_or_names(map, key, p, required, load); break;
    case LoadParameter::Kind::choice: map.choice(key, load.*p.text, p.choices, required); break;
    case LoadParameter::Kind::motion: parse_motion_profile(map, key, load.motion, required); break;
    case LoadParameter::Kind::mapping:
      i = parse_mapping(map, parameters, i, prefix, required, load);
      continue;
    }
    ++i;
  }
}

/// A load: its type, then the keys its member of the load type registry reads.
void parse_load(CheckedMap& map, LoadSettings& load) {
  std::string kind;
  if (!map.choice("type", kind, load_type_names(), true)) {
    map.accept_remaining_keys();
    return;
  }
  const LoadType& type = *find_load_type(kind);
  load.kind = type.kind;
  parse_load_parameters(map, type.parameters, 0, type.parameters.size(), "", load);
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
