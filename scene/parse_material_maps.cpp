// The scene keys of volumes attached to the material: tissue_regions and texture
// (docs/scene-format.md; docs/volumes-and-images.md, "Tissue regions and texture").
#include "scene/declared_keys.hpp"
#include "scene/parse_sections.hpp"

#include <filesystem>

namespace phantasm::scene_detail {

void parse_tissue_regions(YamlContext& context, const YAML::Node& node,
                          std::vector<TissueRegionSettings>& regions) {
  if (!node.IsSequence()) {
    context.problem(node, "tissue_regions",
                    "expected a list of regions {organ, label, tissue[, name]}, found " + describe(node));
    return;
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    CheckedMap entry(context, node[i], "tissue_regions[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    TissueRegionSettings region;
    read_declared_keys(entry, region, {"organ"});
    if (read_declared_keys(entry, region, {"label"}).count("label"))
      check_name(context, entry.get("label"), entry.child_path("label"), region.label);
    read_declared_keys(entry, region, {"tissue"});
    if (read_declared_keys(entry, region, {"name"}).count("name"))
      check_name(context, entry.get("name"), entry.child_path("name"), region.name);
    regions.push_back(region);
  }
}

void parse_texture(CheckedMap& map, const std::filesystem::path& scene_folder, TextureSettings& texture) {
  const std::set<std::string> read = read_declared(map, texture);
  // A relative scan is the scene folder's, as organs' files are (anatomy.organs[].shape.file);
  // whether it exists and covers the anatomy is checked when it is read.
  if (read.count("scan") && !texture.scan.empty() && std::filesystem::path(texture.scan).is_relative())
    texture.scan = (scene_folder / texture.scan).string();
}

} // namespace phantasm::scene_detail
