// Fields between two subjects of one template (docs/subject-pairs.md): a sweep's subjects share
// their reference state, so subject i's field from the template and subject j's field to it
// compose into the field that brings i's images onto j's grid, exact where both are.
#pragma once

#include "evaluation/registration_metrics.hpp"

#include <Eigen/Core>
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

/// A subject's solved bodies (a simulated organ and those nested in it, solved as one tet mesh):
/// the template's tet meshes, which every subject of the template shares, and where the subject's
/// solve took their vertices. Barycentric in a rest tet, carried to the same weights of the solved
/// vertices, is the subject's exact map from the template (the map its fields sample).
struct SolvedBodies {
  std::vector<Eigen::MatrixX4i> tets;
  std::vector<Eigen::MatrixX3d> rest_mm, deformed_mm; ///< RAS mm, per body
};

/// The field from subject i (moving) to subject j (fixed), composed through the template: at a
/// point x of j's deformed state, X = x + v(x) in the template (j's from-ref_to-def field, on j's
/// deformed grid, read at its voxels: no interpolation) and then i's map at X, so the result is
/// u(x) = X + w(X) - x.
///
/// Without i's solved bodies, i's map at X is its from-def_to-ref field w, trilinear, exact where
/// j's field is exact at x and i's at all 8 voxels around X. With them, where X lies in a body's
/// rest tets, i's map is the body's exact one (the solved vertices at X's barycentric weights), exact
/// when the 8 voxels around X are voxels where i's field is exact and is that body map (within
/// 1e-3 mm: not still tissue); outside the bodies, the trilinear field, exact when the 8 voxels are
/// exact and none of them is such a voxel (the field there is the head's affine growth or zero,
/// which trilinear interpolation keeps). A cell holding voxels of both, all exact, is exact where
/// the body's map (extrapolated from its nearest tet outside it) and the affine map outside (fitted
/// to i's exact voxels that are not the body map) agree at X within 0.01 voxel; the value is then
/// the body's map in the body and the affine map outside. The exact mask thus holds the composed
/// map itself, to rounding or to that hundredth of a voxel where X's cell straddles the two.
/// @param moving_from_template i's from-def_to-ref field (ITK: on the template grid)
/// @param moving_exact its exact mask
/// @param template_from_fixed j's from-ref_to-def field (on j's deformed grid)
/// @param fixed_exact its exact mask
/// @param moving_bodies i's solved bodies, or null
/// @throws InputError when a mask does not match its field's voxel count, or the bodies' arrays
///   do not match each other
ComposedField compose_through_template(const DisplacementField& moving_from_template,
                                       const std::vector<std::uint8_t>& moving_exact,
                                       const DisplacementField& template_from_fixed,
                                       const std::vector<std::uint8_t>& fixed_exact,
                                       const SolvedBodies* moving_bodies = nullptr);

/// How far i -> j then j -> i (trilinear, as a tool composes the two files) may miss the identity
/// at a voxel of i -> j's exact mask, in voxels: the tolerance of one subject's two fields.
inline constexpr double pair_round_trip_tolerance_voxels = 0.1;

/// Leaves out of `forward`'s exact mask each voxel x whose round trip, forward's point carried
/// back by `backward` (trilinear), misses x by more than pair_round_trip_tolerance_voxels of the
/// grid's smallest spacing (a cell of `backward` across a kink of its map): the masks of a pair's
/// two fields then invert each other within that tolerance, as one subject's two fields do.
/// @return the voxels left out
std::size_t narrow_to_round_trip(ComposedField& forward, const DisplacementField& backward);

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
/// name, organ, x, y, z in i and in j, RAS mm), and OUT/pairs.tsv listing them. The composition
/// goes through each moving subject's solved bodies (its tet meshes in both states, which the
/// dataset holds in every output profile) and each mask is narrowed to its pair's round trip.
/// Every subject's files are checked before anything is written: its fields, masks and solved
/// tet meshes present, one grid for all, and one template (the same reference labels and rest
/// tet meshes).
/// @return the pairs written with their exact fractions
/// @throws InputError naming the subject, file or option that does not fit; nothing is written
nlohmann::json write_subject_pairs(const PairRequest& request);

} // namespace phantasm
