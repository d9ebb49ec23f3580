// Constraints of surfaces and strings (edge and triangle strain, triangle area, bending) of the
// form w/2 |F - P(F)|^2, and their projections: the shells and sheets of the elastic model.
#pragma once

#include "sim/tet_constraints.hpp"

#include <Eigen/Core>

#include <array>

namespace phantasm {

/// Constraints of surfaces and strings (docs/method.md sections 3.1-3.5), each of the form
/// w/2 |F - P(F)|^2 with F = X Q a 3 x columns matrix linear in the positions X of its vertices.
enum class SurfaceConstraintKind {
  edge_strain,     ///< F = (xj - xi) / L0; P: the same direction, length clamped to the range
  triangle_strain, ///< F the 3x2 in-plane deformation gradient; P: singular values clamped
  triangle_area,   ///< the same F; P: the closest point whose singular values' product (the area
                   ///< ratio) lies in the range
  bending,         ///< F = e, the cotangent edge Laplacian of the edge's 4 vertices; P: e scaled
                   ///< to its rest length (times the range)
};

struct SurfaceElement {
  SurfaceConstraintKind kind = SurfaceConstraintKind::triangle_strain;
  std::array<int, 4> vertices{};
  int count = 0;   ///< vertices used (2 edge, 3 triangle, 4 bending)
  int columns = 1; ///< columns of F (2 for triangles)
  Eigen::Matrix<double, 4, 2> Q = Eigen::Matrix<double, 4, 2>::Zero();
  double weight = 0.0;
  SingularValueRange range; ///< stretch (edges, triangles) or curvature ratio (bending) limits
  /// bending: the rest Laplacian e_rest (its length is the rest curvature; its direction is the
  /// fallback where e vanishes); edges: the rest direction
  Eigen::Vector3d rest = Eigen::Vector3d::Zero();
};

using SurfaceMatrix = Eigen::Matrix<double, 3, 2>; ///< F or P(F); only `columns` columns used

/// F = X Q at positions p (one row per vertex).
SurfaceMatrix surface_deformation(const SurfaceElement& e, const Eigen::MatrixX3d& p);

/// The closest point of the element's set to F.
SurfaceMatrix project_surface(const SurfaceElement& e, const SurfaceMatrix& F);

/// An edge strain element between vertices i and j (rest positions in metres), weight
/// stiffness * L0 (N: stiffness in N/m per unit length... the weight of a unit strain).
SurfaceElement edge_strain_element(int i, int j, const Eigen::MatrixX3d& rest_m, double stiffness,
                                   const SingularValueRange& range = {});

/// A triangle strain element (as-rigid-as-possible membrane; range = stretch limits), weight
/// 2 mu t A (t the thickness, A the rest area). F = X Q with Q mapping the rest triangle's
/// in-plane coordinates.
/// @throws std::invalid_argument for a degenerate rest triangle
SurfaceElement triangle_strain_element(const std::array<int, 3>& v, const Eigen::MatrixX3d& rest_m,
                                       double mu_thickness, const SingularValueRange& range = {});

/// A triangle area element (range: area ratio limits; {1, 1} keeps the area) of the given weight.
/// @throws std::invalid_argument for a degenerate rest triangle
SurfaceElement triangle_area_element(const std::array<int, 3>& v, const Eigen::MatrixX3d& rest_m,
                                     double weight, const SingularValueRange& range = {});

/// A bending element of the edge (v0, v1) with opposite vertices v2 (triangle v0 v1 v2) and v3
/// (triangle v1 v0 v3): e = sqrt(3 / (A0 + A1)) sum_k K_k x_k with K the cotangent weights of
/// Bergou et al. 2006 (so w/2 |e|^2 is their quadratic bending energy for a flat rest state),
/// weight = the bending stiffness (N m). The rest curvature e_rest is kept: P(e) = e / |e| *
/// |e_rest| clamp(|e| / |e_rest|, range).
SurfaceElement bending_element(const std::array<int, 4>& v, const Eigen::MatrixX3d& rest_m, double stiffness,
                               const SingularValueRange& range = {});

} // namespace phantasm
