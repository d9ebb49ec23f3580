#include "scene/declared_keys.hpp"
#include "scene/parse_sections.hpp"
#include "sim/load_type.hpp"

namespace phantasm::scene_detail {
namespace {

/// A load's `key` (its motion: constant, ramp or sine) as LoadSettings' declaration reads it,
/// required as its load type says.
void parse_motion_profile(CheckedMap& map, const std::string& key, bool required, LoadSettings& load) {
  SettingField<LoadSettings> motion = declared_field<LoadSettings>(key);
  motion.required = required;
  CheckedMapReader reader(map);
  read_field(reader, motion, load);
}

/// An obstacle: its type, then the keys that type reads (a sphere's centre is its point_mm),
/// their bounds those of ObstacleSettings' declaration.
void parse_obstacle(CheckedMap& map, ObstacleSettings& obstacle) {
  if (read_declared_keys(map, obstacle, {"type"}).empty()) {
    map.accept_remaining_keys();
    return;
  }
  const NumberRule coordinate = declared_rule<ObstacleSettings>("point_mm");
  if (obstacle.shape == ObstacleShape::half_space) {
    map.vec3("point_mm", obstacle.point_mm, coordinate, true);
    if (map.vec3("normal", obstacle.normal, declared_rule<ObstacleSettings>("normal"), true)) {
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
    map.vec3("center_mm", obstacle.point_mm, coordinate, true);
    map.number("radius_mm", obstacle.radius_mm, declared_rule<ObstacleSettings>("radius_mm"), true);
  }
  read_declared_keys(map, obstacle, {"displacement_mm", "motion", "period_s"});
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

/// A load parameter's range for messages (the load type registry holds it, and the
/// declaration of LoadSettings shows it).
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
    case LoadParameter::Kind::motion: parse_motion_profile(map, key, required, load); break;
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
  read_declared_keys(map, deformation, {"mode"});
  if (map.has("solver")) {
    CheckedMap solver(map.context(), map.get("solver"), map.child_path("solver"));
    if (solver.valid()) read_declared(solver, deformation.solver);
  }
  read_declared(map, deformation, {"mode"}); // time_step_s, frames, fixed, load_steps, volume
  if (map.has("head_scale")) {
    // A change of the whole head after the solve: scale, shape (axes) and the point that stays.
    CheckedMap head(map.context(), map.get("head_scale"), map.child_path("head_scale"));
    if (head.valid()) {
      read_declared(head, deformation.head_scale);
      const Eigen::Vector3d factors = deformation.head_scale.factors();
      if (!(factors.minCoeff() >= 0.7 && factors.maxCoeff() <= 1.3)) {
        const std::string key = head.has("axes") ? "axes" : "scale";
        head.context().problem(head.get(key), head.child_path(key),
                               "expected scale times each of axes within [0.7, 1.3] (a head grown or shrunk "
                               "by at most 30 % along every axis), found " +
                                   format_vector(factors));
      }
      if (deformation.mode == DeformationMode::none && !deformation.head_scale.identity()) {
        map.context().problem(map.get("head_scale"), map.child_path("head_scale"),
                              "expected mode quasi_static or dynamic (the head's size changes the deformed "
                              "state), found mode none");
      }
    }
  }
  read_declared_keys(map, voxelization, {"gap_tissue"});
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
