// The warning for a displacement field that folds inside its exact mask: both fields are checked
// alike (docs/deformation.md, Ground truth).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// The warning for the voxels of a field's exact mask whose Jacobian determinant is <= 0 (or NaN):
/// how many, the smallest determinant, and where, by the labels of the grid the field lives on;
/// those in the background (label 0: no organ's tissue) are counted apart and are not called a
/// fold of tissue. None when every voxel of the mask has a positive determinant.
/// @param field how the warning names the field and its grid, e.g. "from-def_to-ref (reference grid)"
/// @param jacobian det(I + grad u) per voxel
/// @param exact the field's exact mask, per voxel
/// @param labels the labels of the field's grid, per voxel
/// @param label_names the name of each label from 1 (label 1 is label_names[0]); a label beyond
///        them is called "label <n>"
std::optional<std::string> fold_warning(const std::string& field, const std::vector<float>& jacobian,
                                        const std::vector<std::uint8_t>& exact,
                                        const std::vector<std::int32_t>& labels,
                                        const std::vector<std::string>& label_names);

} // namespace phantasm
