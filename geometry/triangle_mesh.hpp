// TriangleMesh (RAS mm vertices, outward triangles) and the checks that a mesh is a closed,
// oriented 2-manifold, as a patch surface's base mesh and a scene's mesh files must be.
#pragma once

#include <Eigen/Core>

#include <string>

namespace phantasm {

/// A triangle mesh: #V by 3 vertex positions (RAS mm) and #F by 3 vertex indices per triangle,
/// counter-clockwise seen from outside for closed surfaces.
struct TriangleMesh {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX3i faces;

  Eigen::Index vertex_count() const { return vertices.rows(); }
  Eigen::Index face_count() const { return faces.rows(); }
  Eigen::Vector3d vertex(Eigen::Index i) const { return vertices.row(i).transpose(); }
};

/// Checks that a mesh is a closed, oriented 2-manifold without degenerate triangles, the base
/// mesh a patch surface needs. Each kind of defect gets its own message naming the element:
/// indices out of range, degenerate triangles (repeated vertex or area below 1e-12 of the
/// squared mean edge length), open edges, non-manifold edges (more than two triangles),
/// inconsistent orientation (an edge used twice in the same direction), non-manifold vertices
/// (a vertex whose triangles form more than one fan), and inward orientation (negative volume).
/// @param what names the mesh in messages, e.g. "organ liver"
/// @throws InputError
void check_closed_manifold(const TriangleMesh& mesh, const std::string& what);

/// Signed volume enclosed by a closed mesh (positive when oriented outward), mm^3.
double enclosed_volume(const TriangleMesh& mesh);

/// Total triangle area, mm^2.
double surface_area(const TriangleMesh& mesh);

/// Mean edge length (each edge of each triangle counted once per triangle), mm.
double mean_edge_length(const TriangleMesh& mesh);

/// The icosahedron subdivided `level` times, projected to the unit sphere: 20 * 4^level
/// triangles, outward.
TriangleMesh unit_icosphere(int level);

} // namespace phantasm
