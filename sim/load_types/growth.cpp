// Growth (atrophy when negative): a change of the rest volume of an organ's tets, or of the tets
// whose centroid lies in atlas regions; the solid organs holding them answer elastically
// (sim/growth.hpp).
#include "core/format.hpp"
#include "sim/load_types/load_keys.hpp"

#include <algorithm>
#include <sstream>

namespace phantasm {
namespace {

/// One growth per organ and per region, of a solid organ.
std::vector<LoadProblem> check_growth(const DeformationSettings& d, std::size_t i,
                                      const std::vector<LoadOrgan>& organs) {
  std::vector<LoadProblem> problems;
  const LoadSettings& load = d.loads[i];
  for (std::size_t j = 0; !load.organ.empty() && j < i; ++j) {
    if (d.loads[j].kind == load.kind && d.loads[j].organ == load.organ)
      problems.push_back({"organ", "expected one growth per organ, found a second for '" + load.organ +
                                       "' (the first is deformation.loads[" + std::to_string(j) + "])"});
  }
  // A region named twice (groups are resolved when the atlas is read, before the anatomy).
  for (std::size_t j = 0; j <= i; ++j) {
    const std::vector<std::string>& earlier = d.loads[j].regions;
    for (std::size_t r = 0; r < load.regions.size(); ++r) {
      const auto end = j == i ? earlier.begin() + static_cast<std::ptrdiff_t>(r) : earlier.end();
      if (d.loads[j].kind == load.kind && std::find(earlier.begin(), end, load.regions[r]) != end)
        problems.push_back({"region", "expected one growth per region, found a second for '" +
                                          load.regions[r] + "' (the first is deformation.loads[" +
                                          std::to_string(j) + "])"});
    }
  }
  for (const LoadOrgan& organ : organs) {
    if (organ.name != load.organ) continue;
    if (!organ.solid)
      problems.push_back({"organ", "expected a solid organ (growth changes the volume of its tets), found '" +
                                       load.organ + "', a surface organ (solid: false)"});
    break;
  }
  return problems;
}

} // namespace

const LoadType& growth_load_type() {
  static const LoadType type = [] {
    const auto in_regions = [](const LoadSettings& load) { return !load.regions.empty(); };
    LoadParameter atlas{"atlas", LoadParameter::Kind::choice};
    atlas.text = &LoadSettings::atlas;
    atlas.choices = {"aal"};
    atlas.required = true;
    atlas.required_with = {"region", "atlas"};
    atlas.recorded = in_regions;
    LoadParameter region{"region", LoadParameter::Kind::name_or_names};
    region.names = &LoadSettings::regions;
    region.required = true;
    region.required_with = {"region", "atlas"};
    region.expected = "a region of the atlas or a list of them (Hippocampus_L, [Hippocampus, cortex])";
    region.recorded = in_regions;
    LoadParameter organ = load_keys::organ();
    organ.excluded_by = {"region", "atlas"};
    organ.recorded = [](const LoadSettings& load) { return load.regions.empty(); };
    LoadType t{
        LoadKind::growth,
        "growth",
        "a change of the rest volume of an organ's tets, or of those in atlas regions, by volume_change "
        "(atrophy when negative)",
        {atlas, region, organ,
         // -1 would leave no tissue.
         load_keys::number("volume_change", &LoadSettings::volume_change, -1.0, 10.0, "", true, true)}};
    t.changes_rest_volume = true;
    t.acts_on = [](const LoadSettings& load, const std::string& name) { return load.organ == name; };
    t.plan = [](const LoadSettings& load) {
      std::ostringstream line;
      line << "growth of " << growth_target(load) << " by " << 100.0 * load.volume_change
           << " % of its rest volume";
      return line.str();
    };
    t.summary = [](const LoadSettings& load) {
      return "the growth of " + growth_target(load) + " by " + format_number(100.0 * load.volume_change) +
             " %";
    };
    t.check = check_growth;
    return t;
  }();
  return type;
}

} // namespace phantasm
