// The boundary of a tet mesh: the triangles that belong to exactly one tet, oriented outward
// (counter-clockwise seen from outside, away from the tet's fourth vertex).
#pragma once

#include <Eigen/Core>

namespace phantasm {

/// The triangles of a tet mesh that belong to exactly one tet, each oriented so that its normal
/// (b - a) x (c - a) points away from the fourth vertex of its tet, i.e. out of the mesh. In the
/// order of their sorted vertex triples; corners in their tet's order, the last two swapped
/// where needed to point out.
/// @param vertices (#V x 3) positions, mm
/// @param tets (#T x 4) vertex indices (either orientation)
/// @return (#B x 3) vertex indices
Eigen::MatrixX3i tet_boundary_faces(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& tets);

} // namespace phantasm
