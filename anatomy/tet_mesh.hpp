// The tetrahedralization of a solid organ (geometry/tet_mesh.hpp's TetMesh) from an implicit
// shape with CGAL Mesh_3 (seeded, repeatable). The deformation stage's bodies are made of them.
#pragma once

#include "anatomy/implicit_shape.hpp"
#include "geometry/tet_mesh.hpp"
#include "geometry/tet_quality.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace phantasm {

/// Shapes nested in one solid: shapes[0] the outermost, parent[k] (< k) the shape that holds
/// shape k (parent[0] = -1). Siblings are disjoint; every shape lies inside its parent.
struct NestedShapes {
  std::vector<const ImplicitShape*> shapes;
  std::vector<int> parent;

  /// The innermost shape holding x (RAS mm), -1 outside shapes[0]: the shapes' own inside tests,
  /// except that where a point of a shape lies outside all its children and every one of them is
  /// a smoothed indicator (label volumes), it goes to the child of the largest indicator when
  /// that exceeds the shape's own share (its indicator less its children's): the labels' argmax,
  /// so that touching labels share an interface.
  int innermost(const Eigen::Vector3d& x) const;
};

/// Quality criteria of a tetrahedralization (CGAL Mesh_3), lengths in mm.
struct TetMeshCriteria {
  double facet_size_mm = 5.0;     ///< upper bound of surface Delaunay ball radii
  double facet_distance_mm = 0.5; ///< upper bound of the surface approximation error
  double facet_angle_deg = 25.0;  ///< lower bound of surface triangle angles
  double cell_size_mm = 5.0;      ///< upper bound of tetrahedron circumradii
  double cell_radius_edge_ratio = 3.0;
  double sliver_bound_deg = 14.0; ///< perturbation and exudation aim at dihedral angles above this
};

/// Criteria that give a boundary of about `boundary_triangles` triangles for a surface of
/// `surface_area_mm2`, with interior cells of the same size.
TetMeshCriteria criteria_for_boundary_size(double surface_area_mm2, int boundary_triangles);

/// Criteria of element size `tet_size_mm` (the scene's anatomy.tet_size_mm): tet circumradii and
/// surface Delaunay ball radii at most tet_size_mm, surface approximation error at most
/// facet_distance_mm (anatomy.tet_facet_distance_mm), or a tenth of tet_size_mm when that is 0.
TetMeshCriteria criteria_for_tet_size(double tet_size_mm, double facet_distance_mm = 0.0);

/// Tetrahedralizes the inside of an implicit shape with CGAL Mesh_3 (sequential, seeded, so the
/// same seed gives the same mesh). Every tet is oriented positively; the boundary triangles are
/// the surface facets of the complex, oriented outward.
/// @throws InputError when the mesher produces no cells (shape smaller than the criteria)
TetMesh mesh_implicit_solid(const ImplicitShape& shape, const TetMeshCriteria& criteria, std::uint32_t seed);

/// Tetrahedralizes the inside of shapes[0] as one conforming mesh of the nested shapes (CGAL
/// Mesh_3 on a labeled domain whose label at x is innermost(x)): every tet lies in one shape's
/// own region (its subdomain, in `subdomains`), and the surfaces between shapes are meshed as
/// triangles of the tets (within facet_distance_mm of them), so a layer thinner than a tet still
/// gets tets of its own. Sequential and repeatable like mesh_implicit_solid; refinement starts
/// from points on every shape's surface (so that small inner shapes are found), which makes the
/// result independent of the seed in practice. Mesh_3's perturbation and exudation remove slivers
/// but cannot always where a layer is thinner than the tets: the slivers left are mended by
/// moving vertices (improve_slivers), peeling flat tets off the boundary, relabelling lone tets
/// and flipping (below), then moving vertices again; measure with min_dihedral_angle_deg.
/// The boundary triangles are the outer surface's only.
/// What mesh_nested_solid did about the slivers Mesh_3 left (sliver_bound_deg).
struct SliverRepairs {
  int vertex_moves = 0; ///< improve_slivers, both passes
  int peeled = 0;       ///< peel_boundary_slivers
  int relabelled = 0;   ///< relabel_stranded_slivers
  int flips = 0;        ///< flip_slivers
  int splits = 0;       ///< split_slivers
  int collapses = 0;    ///< collapse_short_sliver_edges
};

/// @throws InputError when the mesher produces no cells
TetMesh mesh_nested_solid(const NestedShapes& nested, const TetMeshCriteria& criteria, std::uint32_t seed,
                          SliverRepairs* repairs = nullptr);

/// The triangles between tets of different subdomains (each once, oriented outward of the tet
/// of the smaller subdomain index) of a mesh with `subdomains`.
Eigen::MatrixX3i subdomain_interface_faces(const TetMesh& mesh);

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

/// A deterministic partition of the tets into small face-connected groups of about
/// `target_size` tets (the groups whose volume-averaged deformation gradient carries one bulk
/// constraint each, sim/vertex_star_volumes.hpp): greedy region growing over face adjacency.
/// Seeds are taken in order of fewest ungrouped face neighbours (then tet index), so groups
/// start at the boundary of what is left and few tets are left stranded; a group grows by the
/// ungrouped neighbour sharing the most faces with it (then the closest centroid, then the
/// smallest index). Groups left with fewer than target_size / 2 tets join the smallest
/// face-adjacent group of the same label. Tets of different labels (mesh.subdomains when
/// `labels` is empty and the mesh has them: one material per group) are never grouped together.
/// @param target_size tets per group aimed at (>= 1)
/// @param labels per tet, or empty
/// @return groups of tet indices (each tet in exactly one), in order of creation
std::vector<std::vector<int>> group_tets(const TetMesh& mesh, int target_size,
                                         const std::vector<int>& labels = {});

/// The boundary as a closed triangle mesh of its own (the patch base mesh), and for each of its
/// vertices the index of the tet-mesh vertex it is, so that both move together.
TriangleMesh boundary_surface(const TetMesh& mesh, Eigen::VectorXi* tet_vertex_of_surface_vertex);

} // namespace phantasm
