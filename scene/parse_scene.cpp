#include "core/safe_name.hpp"
#include "core/sha256.hpp"
#include "scene/declared_keys.hpp"
#include "scene/parse_sections.hpp"
#include "scene/yaml_documents.hpp"

#include <fstream>
#include <sstream>

namespace phantasm {
namespace scene_detail {

bool check_name(YamlContext& context, const YAML::Node& at, const std::string& key_path,
                const std::string& value) {
  if (is_safe_name(value)) return true;
  context.problem(at, key_path, std::string("expected ") + k_safe_name_rule + ", found " + quote_name(value));
  return false;
}

bool is_bids_label(const std::string& text) {
  if (text.empty()) return false;
  for (const char c : text) {
    if (!std::isalnum(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

void parse_grid(CheckedMap& map, GridSettings& grid) {
  const std::set<std::string> read = read_declared(map, grid);
  if (read.count("orientation") && !direction_from_axis_code(grid.orientation)) {
    map.context().problem(map.get("orientation"), map.child_path("orientation"),
                          "expected a 3-letter axis code with one of R/L, A/P, S/I each (e.g. RAS, "
                          "LPS), found '" +
                              grid.orientation + "'");
  }
}

void parse_materials(CheckedMap& map, std::vector<MaterialSettings>& materials) {
  if (!map.valid()) return;
  for (const auto& pair : map.node()) {
    const std::string name = pair.first.Scalar();
    check_name(map.context(), pair.first, map.child_path(name), name);
    CheckedMap entry(map.context(), map.get(name), map.child_path(name));
    MaterialSettings material;
    material.name = name;
    read_declared(entry, material, {"name"}); // its name is its key
    materials.push_back(material);
  }
}

void parse_tissues(CheckedMap& map, std::vector<TissueOverride>& tissues) {
  if (!map.valid()) return;
  for (const auto& pair : map.node()) {
    const std::string name = pair.first.Scalar();
    check_name(map.context(), pair.first, map.child_path(name), name);
    CheckedMap entry(map.context(), map.get(name), map.child_path(name));
    TissueOverride tissue;
    tissue.tissue = name;
    read_declared(entry, tissue, {"tissue"}); // its tissue is its key
    tissues.push_back(tissue);
  }
}

void parse_voxelization(CheckedMap& map, VoxelizationSettings& voxelization) {
  read_declared(map, voxelization);
}

void parse_acquisition(CheckedMap& map, AcquisitionSettings& acquisition) {
  // The acquired voxel size replaces the oversampling: the two together are refused.
  const std::vector<std::string> sampling = {"kspace", "kspace_oversampling", "acquired_voxel_mm"};
  const std::set<std::string> read = read_declared_keys(map, acquisition, sampling);
  if (read.count("acquired_voxel_mm") && read.count("kspace_oversampling")) {
    map.context().problem(map.get("acquired_voxel_mm"), map.child_path("acquired_voxel_mm"),
                          "expected either acquired_voxel_mm or kspace_oversampling, found both");
  }
  read_declared(map, acquisition, sampling);
}

void parse_outputs(CheckedMap& map, OutputSettings& outputs) {
  if (read_declared_keys(map, outputs, {"subject"}).count("subject") && !is_bids_label(outputs.subject)) {
    map.context().problem(map.get("subject"), map.child_path("subject"),
                          "expected a BIDS label (letters and digits only), found '" + outputs.subject + "'");
  }
  // The profile sets the switches' defaults: a switch the scene gives wins over it.
  if (read_declared_keys(map, outputs, {"profile"}).count("profile") &&
      outputs.profile == OutputProfile::benchmark) {
    outputs.meshes = outputs.vdb = outputs.previews = outputs.fractions = outputs.parameter_maps = false;
  }
  read_declared(map, outputs, {"subject", "profile"});
}

} // namespace scene_detail

using namespace scene_detail;

SceneLoadResult parse_scene(const std::string& text, const std::filesystem::path& file) {
  SceneLoadResult result;
  Scene scene;
  scene.file = file;
  scene.sha256 = sha256_hex(text);
  scene.source_text = text;
  const std::string file_name = file.string();

  YAML::Node root;
  try {
    const std::vector<YAML::Node> documents = load_yaml_documents(text);
    if (documents.size() > 1) {
      // yaml-cpp's Load would read the first and drop the rest without a word.
      const YAML::Mark at = documents[1].Mark();
      result.problems.push_back(Diagnostic{SourceLocation{file_name, at.line + 1, at.column + 1}, "",
                                           "expected one YAML document, found " +
                                               std::to_string(documents.size()) + " (a second '---')"});
      return result;
    }
    if (!documents.empty()) root = documents.front();
  } catch (const YAML::Exception& error) {
    SourceLocation where{file_name, error.mark.line + 1, error.mark.column + 1};
    if (error.mark.is_null()) where.line = where.column = 0;
    result.problems.push_back(
        Diagnostic{where, "", "expected valid YAML, found a syntax error: " + error.msg});
    return result;
  }

  // A sweep given where a scene belongs (phantasm run sweep.yaml) would get a line for every
  // scene key it lacks and every sweep key it has: one says what it is and what reads it.
  if (root.IsMap() && root["phantasm_sweep"] && !root["phantasm"]) {
    const YAML::Mark at = root["phantasm_sweep"].Mark();
    result.problems.push_back(
        Diagnostic{SourceLocation{file_name, at.line + 1, at.column + 1}, "phantasm_sweep",
                   "expected a scene (phantasm: 1, docs/scene-format.md), found a sweep; "
                   "phantasm batch runs a sweep, phantasm validate checks one"});
    return result;
  }

  YamlContext context(file_name, result.problems, scene.locations);
  {
    CheckedMap top(context, root, "");
    if (!top.valid()) return result;
    int format_version = 0;
    if (top.integer("phantasm", format_version, 1, 1, true)) {
      // Only version 1 exists; the key is there so that later formats can be told apart.
    }
    if (top.string("name", scene.name, true)) check_name(context, top.get("name"), "name", scene.name);
    top.unsigned_integer("seed", scene.seed, true);
    read_declared_keys(top, scene.mri, {"field_strength_T"});

    if (top.has("grid")) {
      CheckedMap grid(context, top.get("grid"), "grid");
      if (grid.valid()) parse_grid(grid, scene.grid);
    } else {
      top.missing("grid", "a mapping with field_of_view_mm and voxel_size_mm");
    }
    if (top.has("materials")) {
      CheckedMap materials(context, top.get("materials"), "materials");
      parse_materials(materials, scene.deformation.materials);
    }
    if (top.has("tissues")) {
      CheckedMap tissues(context, top.get("tissues"), "tissues");
      parse_tissues(tissues, scene.mri.tissues);
    }
    if (top.has("anatomy")) {
      CheckedMap anatomy(context, top.get("anatomy"), "anatomy");
      if (anatomy.valid()) parse_anatomy(anatomy, file.parent_path(), scene.anatomy);
    } else {
      top.missing("anatomy", "a mapping with a list of organs");
    }
    if (top.has("deformation")) {
      CheckedMap deformation(context, top.get("deformation"), "deformation");
      if (deformation.valid()) parse_deformation(deformation, scene.deformation, scene.voxelization);
    }
    if (top.has("voxelization")) {
      CheckedMap voxelization(context, top.get("voxelization"), "voxelization");
      if (voxelization.valid()) parse_voxelization(voxelization, scene.voxelization);
    }
    if (top.has("sequences")) parse_sequences(context, top.get("sequences"), scene.mri.sequences);
    if (top.has("acquisition")) {
      CheckedMap acquisition(context, top.get("acquisition"), "acquisition");
      if (acquisition.valid()) parse_acquisition(acquisition, scene.mri.acquisition);
    }
    if (top.has("tissue_regions"))
      parse_tissue_regions(context, top.get("tissue_regions"), scene.mri.regions);
    if (top.has("texture")) {
      CheckedMap texture(context, top.get("texture"), "texture");
      if (texture.valid()) parse_texture(texture, file.parent_path(), scene.mri.texture);
    }
    if (top.has("outputs")) {
      CheckedMap outputs(context, top.get("outputs"), "outputs");
      if (outputs.valid()) parse_outputs(outputs, scene.outputs);
    }
  } // unknown keys are reported here, when the checked maps close

  if (!result.problems.empty()) return result;
  check_consistency(context, scene);
  if (!result.problems.empty()) return result;
  resolve_stage_settings(scene);
  result.scene = std::move(scene);
  return result;
}

std::string read_scene_text(const std::filesystem::path& file, std::string& text) {
  text.clear();
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(file, error);
  if (!std::filesystem::exists(status)) return "found no such file";
  // A folder opens as an empty stream (it would read as a scene with nothing in it); a device
  // such as /dev/zero never ends.
  if (std::filesystem::is_directory(status)) return "found a folder";
  if (std::filesystem::is_character_file(status) || std::filesystem::is_block_file(status))
    return "found a device node";
  if (std::filesystem::is_socket(status)) return "found a socket";
  std::ifstream stream(file, std::ios::binary);
  if (!stream) return "found a file that cannot be opened";
  std::vector<char> buffer(std::size_t{1} << 16);
  while (stream) {
    stream.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    text.append(buffer.data(), static_cast<std::size_t>(stream.gcount()));
    if (text.size() > k_max_scene_file_bytes) {
      text.clear();
      return "found more than " + std::to_string(k_max_scene_file_bytes >> 20) + " MB";
    }
  }
  return {};
}

SceneLoadResult load_scene(const std::filesystem::path& file) {
  std::string text;
  if (const std::string found = read_scene_text(file, text); !found.empty()) {
    SceneLoadResult result;
    result.problems.push_back(
        Diagnostic{SourceLocation{file.string(), 0, 0}, "",
                   (found == "found a file that cannot be opened" ? "expected a readable scene file, "
                                                                  : "expected a scene file, ") +
                       found});
    return result;
  }
  return parse_scene(text, file);
}

} // namespace phantasm
