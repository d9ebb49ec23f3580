// The sliver repairs that follow Mesh_3 on a mesh of nested shapes (mesh_nested_solid,
// anatomy/tet_mesh.hpp), one family per file: moving vertices (sliver_vertex_moves.cpp), peeling
// and relabelling without moving one (sliver_removal.cpp), flips (sliver_flips.cpp), edge splits
// (sliver_splits.cpp) and edge collapses (sliver_collapses.cpp). Each is sequential, in a fixed
// order: the same mesh gives the same result. Their measure is the smallest dihedral angle
// (geometry/tet_quality.hpp).
#pragma once

#include "geometry/tet_mesh.hpp"

#include <Eigen/Core>

#include <functional>

namespace phantasm {

/// What mesh_nested_solid did about the slivers Mesh_3 left (sliver_bound_deg).
struct SliverRepairs {
  int vertex_moves = 0; ///< improve_slivers, both passes
  int peeled = 0;       ///< peel_boundary_slivers
  int relabelled = 0;   ///< relabel_stranded_slivers
  int flips = 0;        ///< flip_slivers
  int splits = 0;       ///< split_slivers
  int collapses = 0;    ///< collapse_short_sliver_edges
};

/// Raises the smallest dihedral angle of tets below bound_deg (slivers) of a mesh with
/// subdomains by moving their vertices, the way a mesher's sliver perturbation does: each vertex
/// of a sliver tries steps of 5-35 % of its mean edge length in fixed directions and keeps the
/// position that most raises the smallest dihedral angle of its tets, provided every one of them
/// stays positively oriented with its centroid in its own subdomain (`label`) and no more of
/// them than before have an angle under 10 degrees (a better sliver, not more of them). A vertex inside
/// one subdomain moves freely; a vertex on an interface (between two subdomains, or one and the
/// outside, label -1) moves in the interface's tangent plane and is put back onto it by
/// bisection of `label` along the normal; a vertex where three meet stays. Besides the fixed
/// directions, each vertex tries the way straight off the face opposite it in each of its slivers
/// (within the tangent plane on an interface). Sequential, in vertex
/// order, up to `passes` passes: the same mesh gives the same result.
/// @param label subdomain at a point (an index into the mesh's subdomains), -1 outside
/// @return how many vertex moves were made
int improve_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label, double bound_deg,
                    int passes = 4);

/// Removes the slivers (a dihedral angle below bound_deg) that lie on the boundary with two of
/// their faces, as a mesher's exudation would: their other two faces become boundary. A sliver
/// whose removal would leave the boundary non-manifold (the edge its two inner faces share is on
/// the boundary already) stays. A mesh's slivers there are flat tets of a layer thinner than
/// the tets (the CSF between skull and cortex): their volume is next to nothing. The boundary
/// faces that remain keep their order; the new ones follow, oriented outward.
/// @return how many tets were removed
int peel_boundary_slivers(TetMesh& mesh, double bound_deg);

/// Gives each sliver that shares more of its faces with another subdomain than with its own (a
/// lone tet of one region wedged between others, all four faces interfaces) the subdomain it
/// shares most faces with (then the larger face area, then the smaller index): a flat tet whose
/// vertices all lie where regions meet cannot be mended by moving them, and its region is a
/// matter of no volume. In tet order; the mesh's vertices and tets do not change.
/// @return how many tets changed subdomain
int relabel_stranded_slivers(TetMesh& mesh, double bound_deg);

/// Replaces slivers (a dihedral angle below bound_deg) by flips inside one subdomain: two tets
/// sharing a face become three around the edge joining their far vertices (2-3), or the n tets
/// around an edge (3 to 7) become 2(n - 2) around a fan of the ring of their other vertices
/// (edge removal; the 3-2 and 4-4 flips among them), when the new tets fill the same volume,
/// raise the smallest dihedral angle of those they replace and count no more under 10 degrees. Faces and
/// edges on an interface or the boundary are never flipped, so interfaces and the boundary keep their
/// triangles; no vertex moves. In tet order, up to `passes` passes: the same mesh gives the same result.
/// @return how many flips were made
int flip_slivers(TetMesh& mesh, double bound_deg, int passes = 4);

/// Splits slivers (a dihedral angle under 10 degrees) that the other repairs leave: one edge of
/// the sliver gets a new vertex, every tet around the edge is cut in two at it, and the vertex is
/// placed where the smallest angle of those tets is largest (steps of 5-50 % of the edge's length
/// in 26 fixed directions and off the sliver's faces; each tet positive and its centroid in its
/// subdomain). An edge inside one subdomain places its vertex freely; an edge on an interface or
/// on the boundary (two separating faces around it, two sides) moves it within that surface and
/// puts it back onto the surface by bisection of `label` along the surface's normal, and the
/// boundary faces on the edge are split too. The split is kept when it raises the smallest angle
/// around the edge and leaves no more tets under 10 degrees; the best of the sliver's edges is
/// taken. In tet order: the same mesh gives the same result.
/// @param label subdomain at a point, -1 outside
/// @return how many vertices were inserted
int split_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label);

/// Collapses the shortest edge of each sliver (a dihedral angle under 10 degrees) whose edge is
/// under a third of the sliver's longest: a vertex where Mesh_3 put two points of one surface or
/// curve next to each other (0.4 mm apart among 5 mm edges). The edge's one vertex goes onto the
/// other, provided the other lies on every surface the first does (its regions, the outside
/// included, hold the first's), every tet stays positive, no face gets more than two tets, the
/// boundary stays a manifold, and the smallest angle of the changed tets rises without more of
/// them under 10 degrees. The tets on the edge go; the vertex left without tets is removed (later
/// vertices are renumbered). In tet order: the same mesh gives the same result.
/// @return how many edges were collapsed
int collapse_short_sliver_edges(TetMesh& mesh);

} // namespace phantasm
