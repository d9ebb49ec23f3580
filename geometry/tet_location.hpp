// Barycentric coordinates of points in tetrahedra, and the tet of a tet mesh that holds a point
// (box-culled search) or, outside the mesh, the tet to extrapolate from.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace phantasm {

/// Barycentric coordinates of x in tet (a, b, c, d): weights w with x = w0 a + w1 b + w2 c + w3 d
/// and sum 1. All are >= 0 exactly when x lies in the tet. The tet must not be flat.
/// @param x, a, b, c, d points, mm
/// @return (4) weights of a, b, c, d
Eigen::Vector4d tet_barycentric(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c, const Eigen::Vector3d& d);

/// A tet of a mesh and the barycentric coordinates of a point in it.
struct TetLocation {
  Eigen::Index tet = -1;                             ///< row of the tet list
  Eigen::Vector4d weights = Eigen::Vector4d::Zero(); ///< of the tet's corners, sum 1
};

/// How far a tet's bounding box is widened when the locator's grid lists it in the cells the box
/// meets, mm: a point whose weights put it in the tet (up to rounding) lies in a cell that lists it.
inline constexpr double k_grid_margin_mm = 1e-6;

/// Point location in a tet mesh at fixed vertex positions: per tet the inverse of its edge matrix
/// (so barycentric coordinates cost one 3x3 product) and its bounding box, and a uniform grid of
/// cells over the mesh's box listing, in list order, the tets whose box meets each cell (so a
/// point inside the mesh tries the few tets of its cell, not the whole list).
class TetMeshLocator {
public:
  TetMeshLocator() = default;
  /// @param vertices (#V x 3) positions, mm
  /// @param tets (#T x 4) vertex indices; no tet may be flat
  TetMeshLocator(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& tets);

  Eigen::Index tet_count() const { return static_cast<Eigen::Index>(m_inverse.size()); }

  /// Barycentric coordinates of x (mm) in tet t, (4) weights of its corners in the order of the tet list.
  Eigen::Vector4d barycentric(Eigen::Index t, const Eigen::Vector3d& x) const {
    const auto i = static_cast<std::size_t>(t);
    const Eigen::Vector3d l = m_inverse[i] * (x - m_origin[i]);
    return {1.0 - l.sum(), l[0], l[1], l[2]};
  }

  /// The first tet (in the order of the list) that holds x: its bounding box, widened by
  /// box_tolerance_mm, holds x and its smallest weight is >= -weight_tolerance. Nothing when no
  /// tet does (x outside the mesh). With box_tolerance_mm at most k_grid_margin_mm, tries the
  /// tets of x's grid cell only (they are all the tets whose box may hold x).
  /// @param x point, mm
  /// @param weight_tolerance how far below zero a weight may be (dimensionless)
  /// @param box_tolerance_mm how far outside a tet's box x may be, mm
  std::optional<TetLocation> find(const Eigen::Vector3d& x, double weight_tolerance = 1e-12,
                                  double box_tolerance_mm = 1e-9) const;

  /// The tet whose smallest weight at x is largest: the first tet holding x (smallest weight >= 0)
  /// when there is one, else the tet x is least outside of, to extrapolate from (continuous
  /// across the faceted boundary), the first in list order of those as little outside. A point
  /// inside tries the tets of its grid cell (every tet holding it is listed there, in list
  /// order); one no tet holds tries the cells in rings around its own until no tet farther out
  /// can be as little outside (a tet whose box x lies D outside of along an axis where the box
  /// is E long has a weight below -D / (3 E)). The tet is -1 for an empty mesh.
  TetLocation nearest(const Eigen::Vector3d& x) const;

  /// Bounding box of the mesh, mm.
  const Eigen::Vector3d& low() const { return m_low; }
  const Eigen::Vector3d& high() const { return m_high; }
  /// Bounding box of tet t, mm.
  const Eigen::Vector3d& tet_low(Eigen::Index t) const { return m_tet_low[static_cast<std::size_t>(t)]; }
  const Eigen::Vector3d& tet_high(Eigen::Index t) const { return m_tet_high[static_cast<std::size_t>(t)]; }

private:
  /// Lists every tet in the grid cells its box (widened by k_grid_margin_mm) meets.
  void build_grid();
  /// The grid cell holding x, -1 outside the grid.
  Eigen::Index cell_of(const Eigen::Vector3d& x) const;
  /// nearest for a point no tet holds.
  TetLocation least_outside(const Eigen::Vector3d& x) const;

  std::vector<Eigen::Matrix3d> m_inverse;
  std::vector<Eigen::Vector3d> m_origin, m_tet_low, m_tet_high;
  Eigen::Vector3d m_low = Eigen::Vector3d::Constant(1e300), m_high = Eigen::Vector3d::Constant(-1e300);
  // The grid: m_cells cells of m_cell_mm from m_grid_low; cell c lists the tets
  // m_cell_tets[m_cell_start[c] .. m_cell_start[c + 1]).
  Eigen::Vector3d m_grid_low = Eigen::Vector3d::Zero();
  Eigen::Array3i m_cells = Eigen::Array3i::Zero();
  double m_cell_mm = 1.0;
  double m_largest_extent_mm = 0.0; ///< of a tet's box along an axis
  std::vector<std::int64_t> m_cell_start;
  std::vector<std::int32_t> m_cell_tets;
};

} // namespace phantasm
