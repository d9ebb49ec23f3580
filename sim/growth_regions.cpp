#include "sim/growth_regions.hpp"

#include "core/edit_distance.hpp"
#include "core/error.hpp"
#include "sim/load_type.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <string>
#include <utility>

namespace phantasm {
namespace {

std::string lowercase_name(std::string text) {
  for (char& c : text)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// The atlas's names (regions and groups) closest to `name`: those containing it or contained
/// in it (case aside), then those within a few edits, at most eight.
std::string close_names(const RegionAtlas& atlas, const std::string& name) {
  const std::string wanted = lowercase_name(name);
  std::vector<std::pair<std::size_t, std::string>> ranked;
  auto consider = [&](const std::string& candidate) {
    const std::string c = lowercase_name(candidate);
    const bool overlaps =
        wanted.size() >= 3 && (c.find(wanted) != std::string::npos || wanted.find(c) != std::string::npos);
    const std::size_t d = overlaps ? 0 : edit_distance(wanted, c);
    if (d <= std::max<std::size_t>(2, wanted.size() / 3)) ranked.emplace_back(d, candidate);
  };
  for (const auto& [region, label] : atlas.regions)
    consider(region);
  for (const auto& [group, members] : atlas.groups)
    consider(group);
  std::sort(ranked.begin(), ranked.end());
  std::string text;
  for (std::size_t k = 0; k < ranked.size() && k < 8; ++k)
    text += (k ? ", " : "") + ranked[k].second;
  return text.empty() ? "none close; the names are in " + atlas.source : text;
}

} // namespace

std::vector<std::vector<std::int32_t>> growth_region_labels(const DeformationSettings& deformation) {
  std::vector<std::vector<std::int32_t>> labels(deformation.loads.size());
  std::map<std::int32_t, std::pair<std::size_t, std::string>> first; // label: load, name given
  for (std::size_t k = 0; k < deformation.loads.size(); ++k) {
    const LoadSettings& load = deformation.loads[k];
    if (!load_type(load.kind).changes_rest_volume || load.regions.empty()) continue;
    const std::string key = "deformation.loads[" + std::to_string(k) + "].region";
    const RegionAtlas* atlas = deformation.region_atlas.get();
    if (atlas == nullptr || atlas->name != load.atlas) {
      throw SettingError(key, "expected the regions of atlas '" + load.atlas +
                                  "' read for this run (the pipeline reads it), found no such atlas");
    }
    for (const std::string& given : load.regions) {
      const auto group = atlas->groups.find(given);
      const std::vector<std::string> names =
          group != atlas->groups.end() ? group->second : std::vector<std::string>{given};
      for (const std::string& name : names) {
        const auto region = atlas->regions.find(name);
        if (region == atlas->regions.end()) {
          throw SettingError(key, "expected a region or group of atlas " + load.atlas + ", found '" + given +
                                      "' (close names: " + close_names(*atlas, given) + ")");
        }
        const auto [earlier, inserted] = first.emplace(region->second, std::make_pair(k, given));
        if (!inserted) {
          const std::string where = "deformation.loads[" + std::to_string(earlier->second.first) + "]";
          throw SettingError(key, "expected one growth per region, found a second for '" + name +
                                      "' (given as '" + given + "'; the first is " + where + ", given as '" +
                                      earlier->second.second + "')");
        }
        labels[k].push_back(region->second);
      }
    }
  }
  return labels;
}

} // namespace phantasm
