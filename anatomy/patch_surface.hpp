// PatchSurface, the free-form surface of a closed organ: each base triangle carries bumps in its
// own frame, so the surface follows its base vertices, the only thing the simulation moves.
#pragma once

#include "anatomy/bump_lattice.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A quadric in a patch's local coordinates (u, v, w):
/// c0 + c1 u + c2 v + c3 w + c4 u^2 + c5 u v + c6 v^2 + c7 u w + c8 v w + c9 w^2.
struct Quadric {
  std::array<double, 10> c{};

  double value(const Eigen::Vector3d& uvw) const;
  Eigen::Vector3d gradient(const Eigen::Vector3d& uvw) const; ///< d/d(u, v, w)
};

/// A bump on a patch: amplitude * Q^3 where Q = 1 - (p - c)^T S (p - c) over the patch's affine
/// coordinates p = (u, v). Its support is an ellipse (extruded along the normal); because Q is
/// written in the triangle's own coordinates, the bump follows its triangle affinely when the
/// vertices move. The ellipse must lie inside the triangle, so bumps vanish on the base edges
/// (C2 where Q = 0) and neighbouring patches meet at the straight base edge.
struct PatchBump {
  Eigen::Vector2d center_uv{1.0 / 3.0, 1.0 / 3.0};        ///< c, in affine coordinates over the edges
  Eigen::Matrix2d shape_uv = Eigen::Matrix2d::Identity(); ///< S, symmetric positive definite
  double amplitude_mm = 0.0;                              ///< peak height along the normal, mm (< 0: inward)

  /// A round bump of `radius_mm` in a triangle whose rest edge dot products are `rest_metric`.
  static PatchBump disc(const Eigen::Vector2d& center_uv, double radius_mm,
                        const Eigen::Matrix2d& rest_metric);
  /// Q at (u, v). Inline: the patch fit asks it of every basis bump at every sample.
  double shape_value(const Eigen::Vector2d& uv) const {
    const Eigen::Vector2d d = uv - center_uv;
    return 1.0 - d.dot(shape_uv * d);
  }
  /// Q expanded into a quadric in (u, v, w) (no w terms; S taken as symmetric): the form the
  /// patch function F sums (PatchSurface::value, gradient and height).
  Quadric quadric() const;
  /// Adds the bump's height a Q^3 [Q > 0] at (u, v) to `height`, its gradient
  /// -6 a Q^2 S d to `gradient` and, when given, its Hessian a Q (24 (S d)(S d)^T - 6 Q S) to
  /// `hessian` (d = (u, v) - c; S taken as symmetric). Inline: the level sets call it for every
  /// bump near every narrow-band point.
  void add_height(const Eigen::Vector2d& uv, double& height, Eigen::Vector2d& gradient,
                  Eigen::Matrix2d* hessian) const {
    const Eigen::Vector2d d = uv - center_uv;
    const Eigen::Vector2d Sd = shape_uv * d;
    const double q = 1.0 - d.dot(Sd);
    if (q <= 0.0) return;
    height += amplitude_mm * q * q * q;
    gradient += -6.0 * amplitude_mm * q * q * Sd;
    if (hessian) add_hessian_term(q, Sd, *hessian);
  }
  /// Adds the bump's Hessian at (u, v) alone (add_height's, the same bits): for a caller that
  /// needs it at some of the points whose heights it sums.
  void add_hessian(const Eigen::Vector2d& uv, Eigen::Matrix2d& hessian) const {
    const Eigen::Vector2d d = uv - center_uv;
    const Eigen::Vector2d Sd = shape_uv * d;
    const double q = 1.0 - d.dot(Sd);
    if (q <= 0.0) return;
    add_hessian_term(q, Sd, hessian);
  }
  /// The ellipse's area in (u, v) coordinates: pi / sqrt(det S).
  double uv_area() const;

private:
  void add_hessian_term(double q, const Eigen::Vector2d& Sd, Eigen::Matrix2d& hessian) const {
    hessian += amplitude_mm * q * (24.0 * Sd * Sd.transpose() - 6.0 * q * shape_uv);
  }
};

/// Bounds of a patch's height h(u, v) = sum_i a_i Q_i(u, v)^3 [Q_i > 0] over its base triangle
/// (u, v >= 0, u + v <= 1), mm.
struct HeightRange {
  double lowest = 0.0;  ///< h >= lowest everywhere on the triangle
  double highest = 0.0; ///< h <= highest everywhere on the triangle
};

/// Rigorous bounds of a patch's height over its triangle, near its true extremes: the sum of
/// the amplitudes is a bound too, but fitted patches carry many narrow bumps side by side (27 per
/// patch on the Colin head), whose heights reach about a fifth of that sum. The triangle is cut
/// into 32^2 sub-triangles; on each, every Q (a concave quadratic) lies between its smallest
/// corner value and its largest plus a third of the largest edge's d^T S d, and a bump counts
/// only where its support's bounding box reaches. Both bounds enclose 0.
HeightRange patch_height_range(const std::vector<PatchBump>& bumps);

/// The local frame of one patch: x = origin + u edge1 + v edge2 + w length_scale normal.
struct PatchFrame {
  Eigen::Vector3d origin, edge1, edge2, normal; ///< current x0, x1 - x0, x2 - x0, unit outward normal
  double length_scale = 1.0;                    ///< L, a fixed rest length (mean rest edge), mm
  Eigen::Matrix3d local_from_world;             ///< maps x - origin to (u, v, w)
};

/// A plane n . x = offset; n points into the patch it bounds.
struct Plane {
  Eigen::Vector3d normal;
  double offset = 0.0;
  double signed_distance(const Eigen::Vector3d& x) const { return normal.dot(x) - offset; }
};

/// Counts from a tessellation.
struct TessellationStats {
  int max_level = 0;             ///< finest subdivision level of any patch (2^level segments per edge)
  double max_deviation_mm = 0.0; ///< largest estimated deviation from the patch surface
};

/// A closed surface made of free-form patches (docs/method.md section 1): each triangle of a closed,
/// oriented base mesh carries perturbations F_t(x) = q(x) + sum_i a_i Q_i(x)^3 [Q_i >= 0] with
/// q(x) = -n . (x - x0); inside is F >= 0. Only the base vertices move in a simulation; the
/// patches follow their triangles.
class PatchSurface {
public:
  /// @param base closed, oriented, manifold base mesh at rest (RAS mm)
  /// @param what names the surface in error messages
  /// @throws InputError naming the defective element of an invalid base mesh
  PatchSurface(TriangleMesh base, const std::string& what);

  /// Replaces the bumps of one patch (and forgets the height bounds held, height_ranges()).
  /// @throws InputError when a bump's ellipse leaves the triangle or its shape is not positive definite
  void set_bumps(Eigen::Index triangle, std::vector<PatchBump> bumps);
  /// Replaces the bumps of every patch (one list per base triangle, in order), as set_bumps of
  /// each would, in parallel over patches (a surface read back holds 10^5 of them).
  /// @throws InputError as set_bumps, for the first patch in order that has a bad bump (and
  ///         then sets none)
  void set_all_bumps(std::vector<std::vector<PatchBump>> bumps);

  /// Every patch's height bounds (patch_height_ranges) when held: computed by
  /// hold_height_ranges() or given by set_height_ranges() (an anatomy read back), null otherwise.
  /// Heights over the base triangles: they hold while the base vertices move.
  const std::vector<HeightRange>* height_ranges() const {
    return m_height_ranges ? &*m_height_ranges : nullptr;
  }
  /// Computes and holds every patch's height bounds (patch_height_ranges; about 40 us per patch
  /// with bumps: the level sets of a fitted organ need them, and a stored anatomy keeps them).
  void hold_height_ranges();
  /// Holds height bounds computed before for these bumps (patch_height_ranges of this surface).
  /// @throws InputError when there is not one per patch, or one is not finite or has its lowest
  ///         above its highest
  void set_height_ranges(std::vector<HeightRange> ranges);
  const std::vector<PatchBump>& bumps(Eigen::Index triangle) const {
    return m_bumps[static_cast<std::size_t>(triangle)];
  }
  /// Which of a patch's bumps may reach each part of its triangle (value, gradient and height sum
  /// only those, bit for bit the sums over every bump).
  const BumpLattice& bump_lattice(Eigen::Index triangle) const {
    return m_lattices[static_cast<std::size_t>(triangle)];
  }

  /// Moves the base vertices (#V by 3, RAS mm); the patches follow.
  void set_positions(const Eigen::MatrixX3d& positions);
  const TriangleMesh& base_mesh() const { return m_base; }
  const Eigen::MatrixX3d& rest_positions() const { return m_rest; }
  Eigen::Index patch_count() const { return m_base.face_count(); }

  PatchFrame frame(Eigen::Index triangle) const;
  /// (u, v, w) of a world point in a patch's frame.
  Eigen::Vector3d local_coordinates(Eigen::Index triangle, const Eigen::Vector3d& x) const;
  /// F_t(x) in mm (positive inside).
  double value(Eigen::Index triangle, const Eigen::Vector3d& x) const;
  /// dF_t/dx.
  Eigen::Vector3d gradient(Eigen::Index triangle, const Eigen::Vector3d& x) const;
  /// Height of the surface above the base point (u, v) along the current normal, mm: the root
  /// of F_t(b + h n) by safeguarded Newton.
  double height(Eigen::Index triangle, double u, double v) const;
  /// The surface point above base point (u, v).
  Eigen::Vector3d surface_point(Eigen::Index triangle, double u, double v) const;

  /// The three clipping planes of a patch, one per edge (x0x1, x1x2, x2x0): each contains its
  /// edge and the mean normal of the two triangles sharing it, so neighbours share the plane.
  std::array<Plane, 3> clipping_planes(Eigen::Index triangle) const;
  /// True when x lies in the patch's wedge (inside all three clipping planes, with tolerance).
  bool in_wedge(Eigen::Index triangle, const Eigen::Vector3d& x, double tolerance_mm = 1e-9) const;

  /// Enclosed volume in mm^3: base polyhedron plus each bump's exact volume.
  double volume() const;
  /// A patch's bump volume over its base triangle's area, mm: constant while the triangle
  /// deforms (the bumps ride in its frame), so an organ's volume is its base polyhedron's plus
  /// the sum of mean_bump_height(t) times each base triangle's area.
  double mean_bump_height(Eigen::Index triangle) const;
  /// Surface area in mm^2, from a tessellation within `max_deviation_mm`.
  double area(double max_deviation_mm) const;
  /// A triangle mesh within `max_deviation_mm` of the surface (estimated at sub-triangle edge
  /// midpoints and centroids). Each patch is subdivided as finely as it needs, up to 2^8 segments
  /// per base edge (stats->max_deviation_mm then tells what remains); shared edges are split at
  /// the same points from both sides, so the result is watertight. The patches' levels are found
  /// in parallel (OpenMP); the result does not depend on the number of threads.
  TriangleMesh tessellate(double max_deviation_mm, TessellationStats* stats = nullptr) const;
  /// The points of one patch's regular subdivision of the given level, row by row
  /// ((i, j) with i + j <= 2^level, u = i / 2^level, v = j / 2^level).
  std::vector<Eigen::Vector3d> patch_grid_points(Eigen::Index triangle, int level) const;

private:
  struct RestTriangle {
    Eigen::Matrix2d metric;  ///< rest edge dot products
    double area = 0.0;       ///< rest area, mm^2
    double length_scale = 1; ///< mean rest edge length, mm
  };
  struct Perturbation {
    Quadric quadric;
    double amplitude_mm;
  };

  /// The quadrics and amplitudes of a patch's bumps.
  /// @throws InputError naming the patch and bump when a bump is not valid (set_bumps)
  std::vector<Perturbation> checked_perturbations(Eigen::Index triangle,
                                                  const std::vector<PatchBump>& bumps) const;

  /// The subdivision level a patch needs; `grid`, when given, receives that level's points
  /// (patch_grid_points), or nothing when the finest level is still not enough.
  int level_for(Eigen::Index triangle, double max_deviation_mm, double* deviation,
                std::vector<Eigen::Vector3d>* grid = nullptr) const;

  std::string m_what;
  TriangleMesh m_base;
  Eigen::MatrixX3d m_rest;
  std::vector<RestTriangle> m_rest_triangles;
  std::vector<std::vector<PatchBump>> m_bumps;
  std::vector<std::vector<Perturbation>> m_perturbations;
  std::vector<BumpLattice> m_lattices;
  std::optional<std::vector<HeightRange>> m_height_ranges;
  Eigen::MatrixX3i m_neighbours; ///< triangle across edge k (k = 0: x0x1, 1: x1x2, 2: x2x0)
};

/// patch_height_range of every patch of a surface, in patch order. The bounds are heights over
/// the base triangles, so they hold while the base vertices move (a deformed copy shares them).
std::vector<HeightRange> patch_height_ranges(const PatchSurface& surface);

} // namespace phantasm
