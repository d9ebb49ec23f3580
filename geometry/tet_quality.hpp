// Element quality of tet meshes: signed volumes, dihedral angles (the sliver measure), mean edge
// length. The tet mesher's sliver repairs (anatomy/sliver_repairs.hpp) and the checks of every
// tet mesh read them.
#pragma once

#include "geometry/tet_mesh.hpp"

#include <Eigen/Core>

#include <array>

namespace phantasm {

/// Signed volume of tet t, mm^3 (positive for the orientation phantasm uses).
double tet_volume(const TetMesh& mesh, Eigen::Index t);
/// Signed volume of the tet (a, b, c, d), mm^3: (b - a) x (c - a) . (d - a) / 6, positive when
/// d lies on the side of the triangle (a, b, c) its normal points to.
double signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d);
/// The corners of `tet` (four vertex indices of the mesh).
std::array<Eigen::Vector3d, 4> tet_corners(const TetMesh& mesh, const Eigen::Vector4i& tet);
/// The six dihedral angles of the tet with corners p, degrees.
std::array<double, 6> dihedral_angles_deg(const std::array<Eigen::Vector3d, 4>& p);
/// The six dihedral angles of tet t, degrees.
std::array<double, 6> tet_dihedral_angles_deg(const TetMesh& mesh, Eigen::Index t);
/// Smallest dihedral angle over all tets, degrees.
double min_dihedral_angle_deg(const TetMesh& mesh);
/// How many tets have a dihedral angle below bound_deg (slivers, for a bound of about 10 degrees).
Eigen::Index tets_with_dihedral_below(const TetMesh& mesh, double bound_deg);
/// Mean length of the tets' edges (each edge once), mm.
double mean_edge_length(const TetMesh& mesh);

} // namespace phantasm
