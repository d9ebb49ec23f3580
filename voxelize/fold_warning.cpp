#include "voxelize/fold_warning.hpp"

#include "core/format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace phantasm {

std::optional<std::string> fold_warning(const std::string& field, const std::vector<float>& jacobian,
                                        const std::vector<std::uint8_t>& exact,
                                        const std::vector<std::int32_t>& labels,
                                        const std::vector<std::string>& label_names) {
  std::map<std::int32_t, long> folded_by_label;
  long folded = 0;
  double smallest = std::numeric_limits<double>::infinity();
  const std::size_t count = std::min({jacobian.size(), exact.size(), labels.size()});
  for (std::size_t v = 0; v < count; ++v) {
    if (!exact[v] || jacobian[v] > 0.0f) continue;
    ++folded;
    ++folded_by_label[labels[v]];
    smallest = std::min(smallest, static_cast<double>(jacobian[v]));
  }
  if (folded == 0) return std::nullopt;
  const long background = folded_by_label.count(0) ? folded_by_label[0] : 0;
  std::string organs;
  for (const auto& [label, n] : folded_by_label) {
    if (label == 0) continue;
    const auto o = static_cast<std::size_t>(label - 1);
    organs += (organs.empty() ? "" : ", ") +
              (label > 0 && o < label_names.size() ? label_names[o] : "label " + std::to_string(label)) +
              " (" + std::to_string(n) + ")";
  }
  std::string text = std::to_string(folded) + " voxels of the exact mask of " + field +
                     " have a Jacobian determinant <= 0 (smallest " +
                     (std::isfinite(smallest) ? format_number(smallest) : std::string("NaN")) + "): ";
  if (!organs.empty())
    text += std::to_string(folded - background) + " in " + organs +
            ": the deformation folds tissue there (see the sim stage's loads)";
  if (background > 0) {
    text += std::string(organs.empty() ? "" : "; ") + std::to_string(background) +
            " in the background (label 0, no organ's tissue): the simulated mesh folds there where it "
            "reaches beyond the labels";
  }
  return text;
}

} // namespace phantasm
