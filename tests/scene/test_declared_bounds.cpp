// The scene parser checks every declared numeric setting with the bounds its declaration shows
// (scene/settings_declarations.cpp): for each declared key with a rule, a scene with a value just
// outside a bound is refused naming the key and the declared range, and one at or just inside it
// is not refused for its range. Generated from the declarations: a bound changed in the parser and
// not in the declaration (or the other way round) fails here.
#include "scene/scene.hpp"
#include "scene/settings_declarations.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

using namespace phantasm;

namespace {

using Keys = std::vector<std::pair<std::string, std::string>>;

/// A mapping in flow style.
std::string flow(const Keys& keys) {
  std::string out;
  for (const auto& [key, value] : keys)
    out += (out.empty() ? "" : ", ") + key + ": " + value;
  return "{" + out + "}";
}

/// `keys` with `key` set to `value` (replaced, or added at the end).
Keys with(Keys keys, const std::string& key, const std::string& value) {
  for (auto& [k, v] : keys)
    if (k == key) {
      v = value;
      return keys;
    }
  keys.emplace_back(key, value);
  return keys;
}

/// The mappings of a scene that hold declared settings, by the struct they fill.
enum class Section {
  top,
  grid,
  material,
  tissue,
  anatomy,
  organ,
  shape,
  deformation,
  solver,
  obstacle,
  voxelization,
  sequence,
  acquisition,
  texture,
  outputs
};

/// A scene whose mapping `section` has `key: value`; the shape's type and the obstacle's type are
/// those that read `key`.
std::string scene_with(Section section, const std::string& key, const std::string& value) {
  const auto at = [&](Section s, Keys keys) {
    return s == section ? with(std::move(keys), key, value) : keys;
  };
  const Keys top = at(Section::top, {{"field_strength_T", "3"}});
  Keys shape = {{"type", "ellipsoid"}, {"center_mm", "[0, 0, 0]"}, {"radii_mm", "20"}};
  if (key == "exponent_1" || key == "exponent_2") shape[0].second = "superquadric";
  if (key == "size_mm" || key == "cells")
    shape = {
        {"type", "box"}, {"center_mm", "[0, 0, 0]"}, {"size_mm", "[20, 20, 20]"}, {"cells", "[2, 2, 2]"}};
  if (key == "label" || key == "smoothing_mm")
    shape = {{"type", "label_volume"}, {"file", "labels.nii.gz"}, {"label", "1"}};
  Keys obstacle = {{"type", "half_space"}, {"point_mm", "[0, 0, -40]"}, {"normal", "[0, 0, -1]"}};
  if (key == "radius_mm") obstacle = {{"type", "sphere"}, {"center_mm", "[0, 0, 40]"}, {"radius_mm", "5"}};
  std::string text = "phantasm: 1\nname: ball\nseed: 7\n";
  for (const auto& [k, v] : top)
    text += k + ": " + v + "\n";
  text +=
      "grid: " + flow(at(Section::grid, {{"field_of_view_mm", "64"}, {"voxel_size_mm", "[2, 2, 4]"}})) + "\n";
  text += "materials:\n  soft: " +
          flow(at(Section::material, {{"youngs_modulus_Pa", "3000"}, {"poisson_ratio", "0.45"}})) + "\n";
  text += "tissues:\n  white_matter: " + flow(at(Section::tissue, {{"T1_ms", "800"}})) + "\n";
  const Keys organ = at(Section::organ, {{"name", "ball"},
                                         {"tissue", "white_matter"},
                                         {"material", "soft"},
                                         {"shape", flow(at(Section::shape, shape))}});
  text += "anatomy: " + flow(with(at(Section::anatomy, {}), "organs", "[" + flow(organ) + "]")) + "\n";
  Keys deformation = at(Section::deformation, {{"mode", "quasi_static"}});
  deformation = with(deformation, "solver", flow(at(Section::solver, {{"max_iterations", "100"}})));
  deformation = with(deformation, "obstacles", "[" + flow(at(Section::obstacle, obstacle)) + "]");
  text += "deformation: " + flow(deformation) + "\n";
  text += "voxelization: " + flow(at(Section::voxelization, {{"supersampling", "2"}})) + "\n";
  const Keys sequence = {{"name", "T1w"},          {"type", "mprage"},     {"TR_ms", "2300"},
                         {"TE_ms", "3"},           {"TI_ms", "900"},       {"flip_deg", "9"},
                         {"echo_spacing_ms", "7"}, {"turbo_factor", "100"}};
  text += "sequences: [" + flow(at(Section::sequence, sequence)) + "]\n";
  text += "acquisition: " + flow(at(Section::acquisition, {{"noise_percent", "1"}})) + "\n";
  text += "texture: " + flow(at(Section::texture, {{"source", "none"}})) + "\n";
  text += "outputs: " + flow(at(Section::outputs, {{"images", "true"}})) + "\n";
  return text;
}

/// The key path of a key of `section` in scene_with's scenes.
std::string path_of(Section section, const std::string& key) {
  switch (section) {
  case Section::top: return key;
  case Section::grid: return "grid." + key;
  case Section::material: return "materials.soft." + key;
  case Section::tissue: return "tissues.white_matter." + key;
  case Section::anatomy: return "anatomy." + key;
  case Section::organ: return "anatomy.organs[0]." + key;
  case Section::shape: return "anatomy.organs[0].shape." + key;
  case Section::deformation: return "deformation." + key;
  case Section::solver: return "deformation.solver." + key;
  case Section::obstacle: return "deformation.obstacles[0]." + key;
  case Section::voxelization: return "voxelization." + key;
  case Section::sequence: return "sequences[0]." + key;
  case Section::acquisition: return "acquisition." + key;
  case Section::texture: return "texture." + key;
  case Section::outputs: return "outputs." + key;
  }
  return key;
}

std::string number_text(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

/// A value of a field in YAML: one number, or three for a vector.
std::string value_text(const std::string& type, double v) {
  const std::string n = number_text(v);
  return type.rfind("3 ", 0) == 0 ? "[" + n + ", " + n + ", " + n + "]" : n;
}

/// The problems of a scene at the key path (or one of its vector's items).
std::vector<Diagnostic> problems_at(const std::string& text, const std::string& path) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : parse_scene(text, "scene.yaml").problems)
    if (d.key_path == path || d.key_path.rfind(path + "[", 0) == 0) found.push_back(d);
  return found;
}

/// The message a value outside the rule gets, as the declaration describes the rule.
std::string expected_of(const std::string& type, const NumberRule& rule) {
  return type.find("integer") != std::string::npos ? rule.describe_integer() : rule.describe();
}

/// Values just outside and just inside (or at) each finite end of the rule.
std::vector<std::pair<double, double>> outside_and_inside(const std::string& type, const NumberRule& rule) {
  const bool integer = type.find("integer") != std::string::npos;
  std::vector<std::pair<double, double>> values;
  const auto step = [integer](double bound) { return integer ? 1.0 : std::max(std::abs(bound), 1.0) * 1e-9; };
  if (std::isfinite(rule.min)) {
    if (rule.min_exclusive)
      values.emplace_back(rule.min, rule.min + step(rule.min));
    else
      values.emplace_back(rule.min - step(rule.min), rule.min);
  }
  if (std::isfinite(rule.max)) {
    if (rule.max_exclusive)
      values.emplace_back(rule.max, rule.max - step(rule.max));
    else
      values.emplace_back(rule.max + step(rule.max), rule.max);
  }
  return values;
}

/// Checks every declared field of S with a rule that `keys` names (empty: every one whose name
/// is a plain key), in `section`; counts the fields checked.
template <typename S>
void check_bounds(Section section, int& checked, const std::vector<std::string>& only = {}) {
  for (const SettingField<S>& f : declared_settings<S>()) {
    if (!f.rule || f.rule->any() || f.derived) continue;
    if (f.name.find_first_of(".[") != std::string::npos) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), f.name) == only.end()) continue;
    const std::string path = path_of(section, f.name);
    const std::string expected = "expected " + expected_of(f.type, *f.rule);
    for (const auto& [outside, inside] : outside_and_inside(f.type, *f.rule)) {
      const std::vector<Diagnostic> refused =
          problems_at(scene_with(section, f.name, value_text(f.type, outside)), path);
      ASSERT_FALSE(refused.empty()) << path << " = " << number_text(outside) << " is accepted; declared "
                                    << f.bounds;
      EXPECT_NE(refused.front().message.find(expected), std::string::npos)
          << path << ": " << refused.front().message << " (declared: " << expected << ")";
      for (const Diagnostic& d : problems_at(scene_with(section, f.name, value_text(f.type, inside)), path))
        EXPECT_EQ(d.message.find(expected_of(f.type, NumberRule{}).substr(0, 8)), std::string::npos)
            << path << " = " << number_text(inside) << " is refused: " << d.message << " (declared "
            << f.bounds << ")";
    }
    ++checked;
  }
}

} // namespace

TEST(DeclaredBounds, TheBaseSceneParses) {
  const SceneLoadResult result = parse_scene(scene_with(Section::top, "field_strength_T", "3"), "scene.yaml");
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
}

TEST(DeclaredBounds, EveryDeclaredNumericKeyIsCheckedWithItsDeclaredBounds) {
  int checked = 0;
  check_bounds<MriSettings>(Section::top, checked, {"field_strength_T"});
  check_bounds<GridSettings>(Section::grid, checked);
  check_bounds<MaterialSettings>(Section::material, checked);
  check_bounds<TissueOverride>(Section::tissue, checked);
  check_bounds<AnatomySettings>(Section::anatomy, checked);
  check_bounds<OrganSettings>(Section::organ, checked);
  check_bounds<ShapeSettings>(Section::shape, checked);
  check_bounds<DeformationSettings>(Section::deformation, checked);
  check_bounds<SolverSettings>(Section::solver, checked);
  check_bounds<ObstacleSettings>(Section::obstacle, checked);
  check_bounds<VoxelizationSettings>(Section::voxelization, checked);
  check_bounds<SequenceSettings>(Section::sequence, checked);
  check_bounds<AcquisitionSettings>(Section::acquisition, checked);
  check_bounds<TextureSettings>(Section::texture, checked);
  check_bounds<OutputSettings>(Section::outputs, checked);
  EXPECT_GE(checked, 50);
}
