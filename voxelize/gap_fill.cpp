#include "voxelize/gap_fill.hpp"

#include "core/error.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <algorithm>

namespace phantasm {

int gap_tissue_index(const std::string& gap_fill, const std::vector<std::string>& tissues) {
  if (gap_fill == "air") return -1;
  const auto found = std::find(tissues.begin(), tissues.end(), gap_fill);
  if (found == tissues.end()) {
    throw SettingError("deformation.gap_tissue",
                       "expected air or the tissue of an organ of this scene (what fills the space a "
                       "moved organ leaves), found '" +
                           gap_fill + "'");
  }
  return static_cast<int>(found - tissues.begin());
}

std::vector<VoxelizedOrgan> gap_organs(const std::string& gap_fill, int tissue, const OrganTable& organs,
                                       const PhantomDeformation& deformation,
                                       const std::vector<VoxelizedOrgan>& reference, StageReport& report) {
  std::vector<bool> moves(organs.size(), false);
  for (std::size_t o = 0; o < organs.size() && o < deformation.organs.size(); ++o) {
    const std::string& by = deformation.organs[o].moved_by;
    moves[o] = by == "solver" || by.rfind("embedded in ", 0) == 0;
  }
  auto voxelized = [&](int o) {
    return std::any_of(reference.begin(), reference.end(),
                       [o](const VoxelizedOrgan& v) { return v.label == o + 1; });
  };
  std::vector<VoxelizedOrgan> gaps;
  std::string left;
  for (const VoxelizedOrgan& organ : reference) {
    const auto o = static_cast<std::size_t>(organ.label - 1);
    const int container = organs[o].parent;
    if (!moves[o] || container < 0 || moves[static_cast<std::size_t>(container)] || !voxelized(container))
      continue;
    VoxelizedOrgan gap;
    gap.level_set = organ.level_set;
    gap.depth = 2 * organs[static_cast<std::size_t>(container)].depth + 1;
    gap.label = static_cast<int>(organs.size()) + 1;
    gap.tissue = tissue;
    gaps.push_back(gap);
    left += (left.empty() ? "" : ", ") + organs[o].name + " in " +
            organs[static_cast<std::size_t>(container)].name;
  }
  if (!gaps.empty()) {
    report.modelled.push_back("the space a moved organ leaves in a container that stays (" + left +
                              ") is filled with " + gap_fill + " (label " +
                              std::to_string(organs.size() + 1) + ", " + k_gap_label_name + ")");
  }
  return gaps;
}

} // namespace phantasm
