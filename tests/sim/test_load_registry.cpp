// The load type registry (sim/load_type.hpp): every load type is a member with its own name, kind,
// help, plan line and entry point, whose declared keys are parsed, checked and recorded in
// provenance from the member.

#include "scene/scene.hpp"
#include "scene/scene_json.hpp"
#include "sim/load_type.hpp"
#include "sim/loads.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

using namespace phantasm;

namespace {

/// A scene of one organ, `lump`, whose loads follow.
const std::string k_scene = R"(phantasm: 1
name: loads
seed: 3
field_strength_T: 1.5
grid: {field_of_view_mm: 80, voxel_size_mm: 4}
anatomy:
  organs:
    - {name: lump, tissue: muscle_skeletal, shape: {type: box, center_mm: [0, 0, 0], size_mm: [40, 40, 40], cells: [2, 2, 2]}}
deformation:
  mode: quasi_static
  loads:
)";

const Eigen::Vector3d k_vector(1.5, 2.5, 3.5);

/// A number the parameter accepts: 1.5, or the middle of its range.
double accepted_number(const LoadParameter& p) {
  const bool above = p.min_exclusive ? 1.5 > p.min : 1.5 >= p.min;
  const bool below = p.max_exclusive ? 1.5 < p.max : 1.5 <= p.max;
  return above && below ? 1.5 : 0.5 * (p.min + p.max);
}

/// The YAML value of a parameter that is not a mapping.
std::string value_yaml(const LoadParameter& p) {
  switch (p.kind) {
  case LoadParameter::Kind::number: return std::to_string(accepted_number(p));
  case LoadParameter::Kind::vector3: return "[1.5, 2.5, 3.5]";
  case LoadParameter::Kind::organ: return "lump";
  case LoadParameter::Kind::organs: return "[lump]";
  case LoadParameter::Kind::name_or_names: return "[Hippocampus_L]";
  case LoadParameter::Kind::choice: return p.choices.front();
  case LoadParameter::Kind::motion: return "ramp";
  case LoadParameter::Kind::mapping: break;
  }
  return "";
}

bool contains(const std::vector<std::string>& keys, const std::string& key) {
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

/// The top-level key of a parameter ("rotation" for "rotation.angle_deg").
std::string top_key(const LoadParameter& p) {
  const std::string key = p.key;
  return key.substr(0, key.find('.'));
}

/// A load of `type` as a YAML flow mapping with every declared key but those `left_out` (top-level
/// keys or key paths).
std::string load_yaml(const LoadType& type, const std::vector<std::string>& left_out) {
  std::string text = std::string("{type: ") + type.name;
  std::string open; // the mapping being written
  for (const LoadParameter& p : type.parameters) {
    const std::string key = p.key;
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos && !open.empty()) {
      text += "}";
      open.clear();
    }
    if (contains(left_out, key) || contains(left_out, top_key(p))) continue;
    if (p.kind == LoadParameter::Kind::mapping) {
      text += ", " + key + ": {";
      open = key;
      continue;
    }
    if (dot == std::string::npos)
      text += ", " + key + ": " + value_yaml(p);
    else
      text += (text.back() == '{' ? "" : ", ") + key.substr(dot + 1) + ": " + value_yaml(p);
  }
  if (!open.empty()) text += "}";
  return text + "}";
}

SceneLoadResult parse_load(const std::string& load) {
  return parse_scene(k_scene + "    - " + load + "\n", "scene.yaml");
}

/// The ways of giving a member's keys: all of them (an alternative excluded by others left out),
/// and for each alternative excluded by others, it without them.
std::vector<std::vector<std::string>> key_choices(const LoadType& type) {
  std::vector<std::string> excluded;
  std::vector<std::vector<std::string>> choices;
  for (const LoadParameter& p : type.parameters) {
    if (p.excluded_by.empty()) continue;
    excluded.emplace_back(p.key);
    choices.push_back(p.excluded_by);
  }
  choices.insert(choices.begin(), excluded);
  return choices;
}

} // namespace

TEST(LoadRegistry, EveryMemberHasItsOwnNameKindHelpPlanAndEntryPoint) {
  const auto& types = load_types();
  const auto& entries = sim_detail::load_entries();
  ASSERT_EQ(types.size(), entries.size());
  const std::vector<std::string> names = load_type_names();
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), types.size());
  for (std::size_t i = 0; i < types.size(); ++i) {
    const LoadType& type = *types[i];
    // Its kind and its name find it, and no other member.
    EXPECT_EQ(&load_type(type.kind), &type) << type.name;
    EXPECT_EQ(find_load_type(names[i]), &type) << type.name;
    EXPECT_STREQ(to_string(type.kind), type.name);
    EXPECT_GT(std::string(type.description).size(), 10u) << type.name;
    EXPECT_FALSE(type.parameters.empty()) << type.name;
    EXPECT_NE(type.acts_on, nullptr) << type.name;
    EXPECT_NE(type.plan, nullptr) << type.name;
    EXPECT_NE(type.summary, nullptr) << type.name;
    EXPECT_EQ(entries[i]->kind, type.kind) << type.name;
    EXPECT_NE(entries[i]->add, nullptr) << type.name;
    EXPECT_EQ(&sim_detail::load_entry(type.kind), entries[i]) << type.name;
  }
  EXPECT_EQ(find_load_type("pressure"), nullptr);
}

// Each member's keys parse into its settings, and provenance records them (an alternative not
// taken is not recorded); its plan line and its name in warnings are made from them.
TEST(LoadRegistry, EveryDeclaredKeyParsesAndIsRecordedInProvenance) {
  for (const LoadType* type : load_types()) {
    for (const std::vector<std::string>& left_out : key_choices(*type)) {
      const std::string yaml = load_yaml(*type, left_out);
      const SceneLoadResult result = parse_load(yaml);
      ASSERT_TRUE(result.scene) << yaml << ": " << format_diagnostics(result.problems);
      const LoadSettings& load = result.scene->deformation.loads.at(0);
      EXPECT_EQ(load.kind, type->kind) << yaml;
      const nlohmann::json j = scene_settings_json(*result.scene)["deformation"]["loads"][0];
      EXPECT_EQ(j["type"], type->name);
      std::set<std::string> keys{"type"};
      for (const LoadParameter& p : type->parameters) {
        const std::string key = p.key;
        if (contains(left_out, key) || contains(left_out, top_key(p))) continue;
        keys.insert(top_key(p));
        const std::size_t dot = key.find('.');
        const nlohmann::json& recorded =
            dot == std::string::npos ? j[key] : j[top_key(p)][key.substr(dot + 1)];
        if (p.kind == LoadParameter::Kind::number) {
          EXPECT_EQ(load.*p.number, accepted_number(p)) << yaml << ": " << key;
          EXPECT_EQ(recorded, accepted_number(p)) << yaml << ": " << key;
        } else if (p.kind == LoadParameter::Kind::vector3) {
          const Eigen::Vector3d expected = p.unit_vector ? k_vector.normalized() : k_vector;
          EXPECT_LT((load.*p.vector - expected).norm(), 1e-15) << yaml << ": " << key;
          EXPECT_EQ(recorded.size(), 3u) << yaml << ": " << key;
        } else if (p.kind == LoadParameter::Kind::organ || p.kind == LoadParameter::Kind::choice) {
          EXPECT_EQ(recorded, load.*p.text) << yaml << ": " << key;
          EXPECT_FALSE((load.*p.text).empty()) << yaml << ": " << key;
        } else if (p.kind == LoadParameter::Kind::organs || p.kind == LoadParameter::Kind::name_or_names) {
          EXPECT_EQ(load.*p.names,
                    std::vector<std::string>{value_yaml(p).substr(1, value_yaml(p).size() - 2)})
              << yaml << ": " << key;
          EXPECT_EQ(recorded, load.*p.names) << yaml << ": " << key;
        } else if (p.kind == LoadParameter::Kind::motion) {
          EXPECT_EQ(load.motion, MotionProfile::ramp) << yaml;
          EXPECT_EQ(recorded, "ramp") << yaml;
        }
      }
      std::set<std::string> written;
      for (const auto& item : j.items())
        written.insert(item.key());
      // Keys recorded beside those given are the member's defaults (a displacement's rotation).
      for (const LoadParameter& p : type->parameters)
        if (!keys.count(top_key(p)) && (p.recorded == nullptr || p.recorded(load))) keys.insert(top_key(p));
      EXPECT_EQ(written, keys) << yaml;
      EXPECT_FALSE(type->plan(load).empty()) << yaml;
      EXPECT_FALSE(type->summary(load).empty()) << yaml;
    }
  }
}

// A required key left out is reported at its path, the keys that would make it optional (or
// exclude it) left out too.
TEST(LoadRegistry, EveryRequiredKeyLeftOutIsReportedAtItsPath) {
  for (const LoadType* type : load_types()) {
    for (const LoadParameter& p : type->parameters) {
      if (!p.required) continue;
      // Its alternative's keys and those of the alternatives excluded by others left out too.
      std::vector<std::string> left_out = key_choices(*type).front();
      left_out.insert(left_out.end(), p.excluded_by.begin(), p.excluded_by.end());
      left_out.emplace_back(p.key);
      if (p.unless != nullptr) left_out.emplace_back(p.unless);
      const std::string yaml = load_yaml(*type, left_out);
      const SceneLoadResult result = parse_load(yaml);
      ASSERT_FALSE(result.scene) << yaml;
      ASSERT_EQ(result.problems.size(), 1u) << yaml << ": " << format_diagnostics(result.problems);
      const std::string problem = result.problems.front().format();
      EXPECT_NE(problem.find(std::string("deformation.loads[0].") + p.key + ": expected"), std::string::npos)
          << yaml << ": " << problem;
      EXPECT_NE(problem.find("found no such key"), std::string::npos) << problem;
    }
  }
}

TEST(LoadRegistry, AnUnknownTypeIsRefusedWithTheListOfMembers) {
  const SceneLoadResult result = parse_load("{type: pressure, organ: lump}");
  ASSERT_FALSE(result.scene);
  ASSERT_EQ(result.problems.size(), 1u) << format_diagnostics(result.problems);
  std::string list;
  for (const LoadType* type : load_types())
    list += (list.empty() ? "" : ", ") + std::string(type->name);
  EXPECT_NE(result.problems.front().format().find("deformation.loads[0].type: expected one of " + list +
                                                  ", found 'pressure'"),
            std::string::npos)
      << result.problems.front().format();
}

// Every organ a member's keys name must be an organ of the scene; the organ it acts on is then
// simulated.
TEST(LoadRegistry, TheOrganAMemberActsOnIsCheckedAndSimulated) {
  for (const LoadType* type : load_types()) {
    for (const std::vector<std::string>& left_out : key_choices(*type)) {
      std::string yaml = load_yaml(*type, left_out);
      const SceneLoadResult result = parse_load(yaml);
      ASSERT_TRUE(result.scene) << yaml << ": " << format_diagnostics(result.problems);
      const LoadSettings& load = result.scene->deformation.loads.at(0);
      bool names_an_organ = false;
      for (const LoadParameter& p : type->parameters) {
        if (p.kind != LoadParameter::Kind::organ && p.kind != LoadParameter::Kind::organs) continue;
        if (contains(left_out, p.key)) continue;
        names_an_organ = true;
        EXPECT_TRUE(type->acts_on(load, "lump")) << yaml;
        EXPECT_FALSE(type->acts_on(load, "cube")) << yaml;
      }
      if (!names_an_organ) continue;
      for (std::size_t at = yaml.find("lump"); at != std::string::npos; at = yaml.find("lump"))
        yaml.replace(at, 4, "cube");
      const SceneLoadResult unknown = parse_load(yaml);
      ASSERT_FALSE(unknown.scene) << yaml;
      EXPECT_NE(format_diagnostics(unknown.problems)
                    .find("expected the name of an organ in this scene, found 'cube'"),
                std::string::npos)
          << format_diagnostics(unknown.problems);
    }
  }
}
