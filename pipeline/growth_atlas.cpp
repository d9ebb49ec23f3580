#include "pipeline/growth_atlas.hpp"

#include "atlas/atlas_regions.hpp"
#include "atlas/colin27_head.hpp"
#include "sim/growth_regions.hpp"
#include "sim/load_type.hpp"

#include <memory>
#include <string>

namespace phantasm {

DeformationSettings with_growth_atlas(const DeformationSettings& deformation, StageReport& report,
                                      Reporter& reporter) {
  DeformationSettings result = deformation;
  for (const LoadSettings& load : deformation.loads) {
    if (!load_type(load.kind).changes_rest_volume || load.regions.empty()) continue;
    if (result.region_atlas && result.region_atlas->name == load.atlas) continue;
    AtlasRegions read = read_atlas_regions(load.atlas, default_colin27_templates_dir());
    for (const std::string& line : read.provenance) {
      report.modelled.push_back(line);
      reporter.modelled(report.stage, line);
    }
    auto atlas = std::make_shared<RegionAtlas>();
    atlas->name = load.atlas;
    atlas->source = read.source;
    atlas->grid = read.grid;
    atlas->labels = std::move(read.labels);
    atlas->regions = std::move(read.regions);
    atlas->groups = std::move(read.groups);
    result.region_atlas = std::move(atlas);
  }
  growth_region_labels(result); // every region named, none twice
  return result;
}

} // namespace phantasm
