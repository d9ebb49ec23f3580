// The scene keys of volumes attached to the material: tissue_regions and texture
// (docs/scene-format.md; docs/volumes-and-images.md, "Tissue regions and texture").
#include "scene/parse_sections.hpp"

#include <filesystem>

namespace phantasm::scene_detail {

void parse_tissue_regions(YamlContext& context, const YAML::Node& node,
                          std::vector<TissueRegionSettings>& regions) {
  if (!node.IsSequence()) {
    context.problem(node, "tissue_regions",
                    "expected a list of regions {organ, label, tissue}, found " + describe(node));
    return;
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    CheckedMap entry(context, node[i], "tissue_regions[" + std::to_string(i) + "]");
    if (!entry.valid()) continue;
    TissueRegionSettings region;
    entry.string("organ", region.organ, true);
    if (entry.string("label", region.label, true))
      check_name(context, entry.get("label"), entry.child_path("label"), region.label);
    entry.string("tissue", region.tissue, true);
    regions.push_back(region);
  }
}

void parse_texture(CheckedMap& map, const std::filesystem::path& scene_folder, TextureSettings& texture) {
  std::string source;
  if (map.choice("source", source, {"none", "scan", "random"}))
    texture.source = source == "scan"     ? TextureSource::scan
                     : source == "random" ? TextureSource::random
                                          : TextureSource::none;
  map.string_list("tissues", texture.tissues);
  // A relative scan is the scene folder's, as organs' files are (anatomy.organs[].shape.file);
  // whether it exists and covers the anatomy is checked when it is read.
  if (map.string("scan", texture.scan) && !texture.scan.empty() &&
      std::filesystem::path(texture.scan).is_relative())
    texture.scan = (scene_folder / texture.scan).string();
  map.number("T1_gain", texture.T1_gain, between(0.0, 5.0, ""));
  map.number("PD_gain", texture.PD_gain, between(0.0, 5.0, ""));
  map.number("max_deviation", texture.max_deviation, NumberRule{0.0, 0.9, true, false, ""});
  map.number("random_sd", texture.random_sd, between(0.0, 0.5, ""));
  map.number("correlation_mm", texture.correlation_mm, between(0.0, 50.0, "mm"));
}

} // namespace phantasm::scene_detail
