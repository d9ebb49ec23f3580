// TetMesh, a tetrahedral mesh (positively oriented tets, outward boundary triangles, optional
// subdomain per tet): the type the anatomy stage makes, the deformation stage moves and io writes.
#pragma once

#include <Eigen/Core>

namespace phantasm {

/// A tetrahedral mesh of a solid (an organ, or a body of nested organs).
struct TetMesh {
  Eigen::MatrixX3d vertices; ///< #V by 3 positions, RAS mm
  Eigen::MatrixX4i tets;     ///< #T by 4 vertex indices, positively oriented
  /// #B by 3 boundary triangles (indices into vertices), counter-clockwise seen from outside.
  Eigen::MatrixX3i boundary_faces;
  /// Meshes of nested shapes (mesh_nested_solid): #T, per tet the index of the innermost shape
  /// holding it (into NestedShapes::shapes); empty for a mesh of one shape.
  Eigen::VectorXi subdomains;
};

} // namespace phantasm
