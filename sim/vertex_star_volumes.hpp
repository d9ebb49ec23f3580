#pragma once
// The bulk (lambda) term of tet bodies on vertex stars instead of single tets: linear tets
// with one volume constraint each lock as nu -> 1/2 (about 5-6 tets per vertex against 3
// degrees of freedom per vertex); one constraint per vertex star does not (docs/deformation.md).

#include "anatomy/tet_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/sim_settings.hpp"

#include <vector>

namespace phantasm {

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

/// Moves the bulk term of the tets of each group onto one constraint for the group on its
/// volume-averaged deformation gradient (a TetGroup, mean dilatation): F_g = sum_t V_t F_t / V_g,
/// energy w/2 |F_g - P_volume(F_g)|^2 with w = 3 sum_t lambda_t V_t, so a uniform strain costs
/// exactly what the per-tet terms cost. One constraint per group of about 5 tets (a hexahedral
/// cell: fewer constraints than vertices, as Q1/P0's one pressure per hexahedron; or a cluster
/// from group_tets) no longer locks where the per-tet term and vertex stars do
/// (docs/deformation.md). F_g is linear in the positions, so local/global takes the group like a
/// tet (w G G^T in its constant matrix) and Newton its projected Hessian. The groups' tets'
/// volume weights become 0 (or at most `kept_per_tet` times their strain weights); tets in no
/// group keep theirs.
/// Appended to model.tet_groups.
/// @param groups tet indices into model.tets, each tet in at most one group
/// @param kept_per_tet the bulk weight each grouped tet keeps, over its strain weight (the group
///        takes the rest of its bulk weight): a uniform strain still costs what the per-tet term costs
/// @return the number of groups added (groups without a bulk term add none)
/// @throws std::invalid_argument for a tet index out of range or in two groups, or a negative or
///         infinite kept_per_tet
int move_bulk_to_tet_groups(ElasticModel& model, const std::vector<std::vector<int>>& groups,
                            double kept_per_tet = 0.0);

/// The Hessian of a tet group's energy w/2 |F_g - P_volume(F_g)|^2 with respect to its vertices
/// (3n x 3n, rows 3k .. 3k + 2 the coordinates of g.vertices[k]): (G (x) I3) H_F (G^T (x) I3)
/// with H_F the 9x9 Hessian in F of tet_constraints.hpp's projected_hessian (Newton's block).
/// @param clamp_negative false: the exact Hessian (for tests)
Eigen::MatrixXd tet_group_hessian(const ElasticModel& model, const TetGroup& g, const Eigen::MatrixX3d& p,
                                  bool clamp_negative = true);

/// Tets per group of an unstructured body (group_tets' target size, anatomy/tet_mesh.hpp): the
/// smallest size whose bulk term did not lock on the CGAL-meshed cantilever
/// (docs/deformation.md, bench/volume_locking).
inline constexpr int tets_per_group = 8;

/// The bulk weight `tet_groups_and_tets` leaves on each tet, over the tet's strain weight 2 mu V
/// (at most its whole bulk weight 3 lambda V; the group takes the rest): the tets' own term is a
/// bulk modulus of at most 2/3 ratio mu whatever lambda, so it does not grow as nu -> 1/2. 20:
/// the smallest of 1, 10, 20 that left no tet of the coarse Colin head inverted (1 and 10 left 2
/// and 1), and the cantilever's tip from nu 0.45 to 0.499 within 5 % (-3.2 %; 40: -5.6 %)
/// (docs/deformation.md, Volume locking).
inline constexpr double tet_bulk_ratio = 20.0;

/// Applies `formulation` to the tets model.tets[first_tet ..] of one body meshed by `mesh`
/// (tet_group: group_tets(mesh, tets_per_group, labels); tet_group_and_tet: the same groups
/// with at most tet_bulk_ratio times the strain weight of bulk weight left per tet; vertex_star: the stars of
/// the whole tets whose bulk term is still theirs, see move_bulk_to_vertex_stars; tet: nothing).
/// @param labels per tet of the mesh (e.g. its organ), or empty: tets of different labels are
///        not grouped together
/// @return the groups or stars added
int apply_volume_formulation(ElasticModel& model, VolumeFormulation formulation, const TetMesh& mesh,
                             std::size_t first_tet, const std::vector<int>& labels = {});

} // namespace phantasm
