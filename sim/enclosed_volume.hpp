// The patch volume constraint: the volume a closed patch surface encloses kept within a range of
// its rest volume (a fluid-filled organ simulated as a shell), and its projection.
#pragma once

#include "sim/tet_constraints.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace phantasm {

/// The patch volume constraint (docs/method.md sections 1.5 and 3.6): the volume enclosed by a closed
/// surface of patches, kept within [min, max] times its rest volume, e.g. a fluid-filled organ
/// simulated as a shell. A patch's volume is the signed volume of the tet (origin, x0, x1, x2)
/// plus its bumps' volume; the bumps ride in the base triangle's frame with heights in a fixed
/// length, so their volume is the base area times a constant mean height h:
///   V(X) = sum_t [ x0 . (x1 x x2) / 6 + h_t A_t(X) ].
/// The constraint's set is {Y : V(Y) / V0 in [min, max]} over the surface's vertices X; its
/// energy w/2 |X - P(X)|^2 with P the closest point of the set (F = X and Q the identity in the terms of
/// docs/method.md section 2.1: the global matrix gains w on the diagonal of each vertex).
struct EnclosedVolume {
  std::vector<int> vertices; ///< model vertices of the surface
  std::vector<std::array<int, 3>>
      triangles;                     ///< into `vertices`, outward (counter-clockwise seen from outside)
  std::vector<double> bump_height_m; ///< per triangle: bump volume / base area (empty: flat patches)
  double rest_volume_m3 = 0.0;
  SingularValueRange range; ///< limits of V / V0
  double weight = 0.0;      ///< w, N/m
  /// A tet body's vertex star (sim/vertex_star_volumes.hpp): few vertices, so Newton takes the
  /// rank-one Gauss-Newton block w n n^T (n = grad V / |grad V|) over them instead of w I.
  bool vertex_star = false;
};

/// The constraint of a closed surface at rest positions `rest_m` (model rows), with weight
/// w = K |grad V|^2 / V0 for the bulk modulus K: near the set w/2 dist^2 = K (V - V0)^2 / (2 V0),
/// the energy of a fluid of that compressibility, whatever the mesh resolution.
/// @throws std::invalid_argument when the surface encloses no positive volume (open, or inward)
EnclosedVolume enclosed_volume_constraint(std::vector<int> vertices,
                                          std::vector<std::array<int, 3>> triangles,
                                          std::vector<double> bump_height_m, const Eigen::MatrixX3d& rest_m,
                                          double bulk_modulus_Pa, const SingularValueRange& range = {});

/// The surface's vertex positions (one row per entry of c.vertices) out of model positions.
Eigen::MatrixX3d gather_vertices(const EnclosedVolume& c, const Eigen::MatrixX3d& p);

/// V(X) for the surface's vertex positions X.
double enclosed_volume(const EnclosedVolume& c, const Eigen::MatrixX3d& X);

/// dV/dX, one row per surface vertex.
Eigen::MatrixX3d enclosed_volume_gradient(const EnclosedVolume& c, const Eigen::MatrixX3d& X);

/// The closest point P(X) of the set: X itself inside, else the Y with V(Y) at the nearer limit
/// and Y - X parallel to grad V(Y) (the Lagrange condition), by fixed-point iteration on Y with
/// the multiplier solved by Newton's method along grad V at each step (to 1e-13 of the
/// surface's size; converges quickly while |Y - X| is small against the surface's curvature
/// radius; past 100 iterations the last Y, whose volume is at the limit, is returned).
Eigen::MatrixX3d project_enclosed_volume(const EnclosedVolume& c, const Eigen::MatrixX3d& X);

} // namespace phantasm
