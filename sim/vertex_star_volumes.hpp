#pragma once
// The bulk (lambda) term of tet bodies on vertex stars instead of single tets: linear tets
// with one volume constraint each lock as nu -> 1/2 (about 5-6 tets per vertex against 3
// degrees of freedom per vertex); one constraint per vertex star does not (docs/deformation.md).

#include "sim/elastic_model.hpp"

#include <vector>

namespace phantasm {

/// Where the tets' bulk (lambda) energy lives.
enum class VolumeFormulation {
  tet,         ///< per tet: wv/2 |F - P_volume(F)|^2 with wv = 3 lambda V (locks as nu -> 1/2)
  vertex_star, ///< per vertex: the volume of the union of its tets, an EnclosedVolume with K = lambda / 4
  tet_group    ///< per group of tets (e.g. the 5 tets of a hexahedral cell): one volume each, K = lambda
};

/// Moves the bulk term of every tet of the model onto vertex stars: for each vertex touched by
/// a tet with a volume weight, the union of its tets (its star) becomes an EnclosedVolume of
/// the star's boundary triangles (faces shared by two of its tets cancel), range
/// model.volume_range and bulk modulus K_v = sum_t lambda_t V_t / (4 V_v) over its tets t
/// (V_v = sum_t V_t): each tet lies in 4 stars, so for a uniform volumetric strain theta the
/// stars' energy sum_v K_v (theta V_v)^2 / (2 V_v) = sum_t lambda_t theta^2 V_t / 2, the
/// per-tet term's small-strain energy. The tets' volume weights become 0 (their strain
/// weights 2 mu V stay). The stars are appended to model.volumes (flagged vertex_star) after
/// the volumes already there. Call after every body has been added.
/// @param model the model (positions in metres); changed in place
/// @return the number of stars added
int move_bulk_to_vertex_stars(ElasticModel& model);

/// Moves the bulk term of the tets of each group onto one volume constraint for the group: the
/// union of its tets becomes an EnclosedVolume of its boundary triangles, range
/// model.volume_range, bulk modulus K_g = sum_t lambda_t V_t / V_g (V_g = sum_t V_t), so for a
/// uniform volumetric strain theta its energy K_g (theta V_g)^2 / (2 V_g) = sum_t lambda_t
/// theta^2 V_t / 2, the per-tet term's. One constraint per group of about 5 tets (a hexahedral
/// cell: fewer constraints than vertices, as Q1/P0's one pressure per hexahedron) no longer locks
/// where the per-tet term and vertex stars do (docs/deformation.md). The groups' tets' volume
/// weights become 0; tets in no group keep theirs. The volumes are appended to model.volumes
/// (flagged vertex_star: Newton's rank-one block).
/// @param groups tet indices into model.tets, each tet in at most one group
/// @return the number of volumes added (groups without a bulk term add none)
/// @throws std::invalid_argument for a tet index out of range or in two groups
int move_bulk_to_tet_groups(ElasticModel& model, const std::vector<std::vector<int>>& groups);

} // namespace phantasm
