// Fields between two subjects of one template (docs/subject-pairs.md): a sweep's subjects share
// their reference state, so subject i's field from the template and subject j's field to it
// compose into the field that brings i's images onto j's grid, exact where both are.
#pragma once

#include "evaluation/registration_metrics.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace phantasm {

/// A pair of subject labels: (moving, fixed). Its field brings the moving subject's images
/// onto the fixed subject's grid.
using SubjectPair = std::pair<std::string, std::string>;

/// A composed field with where it is exact (1) or rests on a smooth extension (0).
struct ComposedField {
  DisplacementField field;
  std::vector<std::uint8_t> exact; ///< field.grid.voxel_count(), i fastest
};

/// The field from subject i (moving) to subject j (fixed), composed through the template:
/// at a point x of j's deformed state, X = x + v(x) in the template (j's from-ref_to-def field,
/// on j's deformed grid) and X + w(X) in i's deformed state (i's from-def_to-ref field, on the
/// template's grid, trilinear), so the result is u(x) = X + w(X) - x. Exact where j's field is
/// exact at x and i's at all 8 voxels around X (X on the grid).
/// @param moving_from_template i's from-def_to-ref field (ITK: on the template grid)
/// @param moving_exact its exact mask
/// @param template_from_fixed j's from-ref_to-def field (on j's deformed grid)
/// @param fixed_exact its exact mask
/// @throws InputError when a mask does not match its field's voxel count
ComposedField compose_through_template(const DisplacementField& moving_from_template,
                                       const std::vector<std::uint8_t>& moving_exact,
                                       const DisplacementField& template_from_fixed,
                                       const std::vector<std::uint8_t>& fixed_exact);

/// Which pairs `phantasm pair` writes.
struct PairRequest {
  std::filesystem::path dataset;   ///< a folder `phantasm batch` wrote
  std::filesystem::path out;       ///< made; must be new or empty
  std::vector<SubjectPair> listed; ///< pairs named (unordered: both directions are written)
  std::size_t random_count = 0;    ///< else this many distinct pairs drawn with the seed
  std::uint64_t seed = 0;
  // Neither: every pair of the dataset's subjects.
};

/// The unordered pairs of `subjects` a request chooses: the listed ones (each subject checked
/// to be one of `subjects`), `random_count` distinct pairs drawn with the seed (the same pairs for
/// the same seed), or all, each as (lower label, higher label), sorted.
/// @throws InputError naming a subject not in the dataset, a pair of one subject, or more random
///   pairs than there are
std::vector<SubjectPair> choose_pairs(const std::vector<std::string>& subjects, const PairRequest& request);

/// Parses "01:02,03:05" into pairs. @throws InputError naming the text that does not parse
std::vector<SubjectPair> parse_pair_list(const std::string& text);

/// Writes, for each chosen pair and both its directions, OUT/from-<i>_to-<j>/ with the composed
/// field (from-<i>_to-<j>_mode-image_xfm.nii.gz: ITK convention, on j's grid), its exact mask
/// (_desc-exact_mask.nii.gz) and the corresponding landmarks of both subjects (landmarks.csv:
/// name, organ, x, y, z in i and in j, RAS mm), and OUT/pairs.tsv listing them. Every subject's
/// files are checked before anything is written: its fields and masks present, one grid for
/// all, and one template (the same reference labels).
/// @return the pairs written with their exact fractions
/// @throws InputError naming the subject, file or option that does not fit; nothing is written
nlohmann::json write_subject_pairs(const PairRequest& request);

} // namespace phantasm
