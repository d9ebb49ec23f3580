// The surface of any closed implicit shape as a closed, manifold triangle mesh with vertices on
// it (CGAL Mesh_3, seeded): the base mesh of shapes that are not star-shaped.
#pragma once

#include "anatomy/implicit_shape.hpp"
#include "geometry/triangle_mesh.hpp"

#include <cstdint>

namespace phantasm {

/// Size and accuracy of an extracted surface mesh, lengths in mm.
struct SurfaceMeshCriteria {
  double facet_size_mm = 5.0;     ///< upper bound of surface Delaunay ball radii
  double facet_distance_mm = 0.5; ///< upper bound of the distance between facets and the surface
  double facet_angle_deg = 25.0;  ///< lower bound of triangle angles
};

/// The surface of an implicit shape as a closed, outward-oriented, manifold triangle mesh whose
/// vertices lie on the shape (CGAL Mesh_3 restricted to its surface facets, with the manifold
/// criterion). It needs no centre and no star shape: any closed shape of any genus, several
/// components (a shell's inner and outer walls) included, as long as facet_distance_mm resolves
/// its thinnest parts. Sequential and seeded, output in a canonical order (vertices by position),
/// so the same arguments give the same bytes.
/// @param shape closed target, positive inside, inside the ball of radius 1.05 bounding_radius()
///        about center()
/// @throws InputError when the mesher finds no surface
TriangleMesh extract_surface(const ImplicitShape& shape, const SurfaceMeshCriteria& criteria,
                             std::uint32_t seed);

/// The surface of an implicit shape with about `triangles` triangles (within some 20 %): a first
/// extraction measures the area, which sets the facet size of the second (as
/// criteria_for_boundary_size does for tet meshes), and a third corrects the count when the
/// second is off by more than 20 %.
TriangleMesh extract_surface_of_size(const ImplicitShape& shape, int triangles, std::uint32_t seed);

} // namespace phantasm
