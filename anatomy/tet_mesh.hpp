// The tetrahedralization of a solid organ (geometry/tet_mesh.hpp's TetMesh) from an implicit
// shape with CGAL Mesh_3 (seeded, repeatable), the sliver repairs after it
// (anatomy/sliver_repairs.hpp), and the tets' groups and boundary surface. The deformation
// stage's bodies are made of them.
#pragma once

#include "anatomy/implicit_shape.hpp"
#include "anatomy/sliver_repairs.hpp"
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
/// @param repairs when given, what the sliver repairs (anatomy/sliver_repairs.hpp) did
/// @throws InputError when the mesher produces no cells
TetMesh mesh_nested_solid(const NestedShapes& nested, const TetMeshCriteria& criteria, std::uint32_t seed,
                          SliverRepairs* repairs = nullptr);

/// The triangles between tets of different subdomains (each once, oriented outward of the tet
/// of the smaller subdomain index) of a mesh with `subdomains`.
Eigen::MatrixX3i subdomain_interface_faces(const TetMesh& mesh);

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
