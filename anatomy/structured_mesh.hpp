// Structured meshes of simple shapes: a box of hexahedra split into tets and a rectangular
// sheet of triangles (the simulator's benchmark bar and scene boxes and sheets).
#pragma once

#include "anatomy/tet_mesh.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace phantasm {

/// A box of `cells` hexahedra, each split into 5 tetrahedra (alternating so neighbouring cells
/// share their face diagonals): (nx+1)(ny+1)(nz+1) vertices, 5 nx ny nz tets. Centred at the
/// origin with edge lengths size_mm, then rotated and moved to center_mm.
TetMesh structured_box(const Eigen::Vector3d& size_mm, const Eigen::Vector3i& cells,
                       const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_mm);

/// The tets of structured_box(..., cells, ...) grouped by hexahedral cell: cell c holds tets
/// 5c .. 5c + 4 (the groups of one bulk constraint per cell, as Q1/P0's one pressure per
/// hexahedron; sim/vertex_star_volumes.hpp).
std::vector<std::vector<int>> structured_box_cells(const Eigen::Vector3i& cells);

/// A rectangular sheet in its local xy plane of nx by ny quads, each split into 2 triangles
/// (an open surface; normal along local +z).
TriangleMesh structured_sheet(const Eigen::Vector2d& size_mm, const Eigen::Vector2i& cells,
                              const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_mm);

} // namespace phantasm
