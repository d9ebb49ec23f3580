// Fitting a patch surface to an implicit target: base mesh (icosphere or extracted surface),
// vertex placement, least-squares bumps, volume correction, and the fit's measured accuracy.
#pragma once

#include "anatomy/implicit_shape.hpp"
#include "anatomy/patch_surface.hpp"

#include <cstdint>
#include <vector>

namespace phantasm {

/// Where a patch fit's base mesh comes from.
enum class BaseMeshSource {
  automatic, ///< icosphere for star-shaped targets (ImplicitShape::star_shaped()), surface otherwise
  icosphere, ///< an icosphere cast onto the target along rays from its centre (star shapes only)
  surface,   ///< the target's own surface, extracted and meshed to the requested size (any shape)
};

/// Settings of a patch fit: the anatomy's speed/accuracy knob is the base mesh size.
struct PatchFitOptions {
  /// Requested base size: an icosphere of 20 * 4^k <= this (at least 20), or an extracted
  /// surface of about this many triangles.
  int base_triangles = 320;
  BaseMeshSource base_mesh = BaseMeshSource::automatic;
  std::uint32_t seed = 0;       ///< seed of the surface extraction (any fixed value is repeatable)
  int bump_levels = 2;          ///< bumps on the incircles of subdivision levels 0..bump_levels (1 + 4 + 16)
  int sample_level = 5;         ///< least-squares samples on this level's interior grid points per patch
  double regularization = 1e-6; ///< Tikhonov weight relative to the normal matrix's mean diagonal
  /// Base vertices move outward by this fraction of their edges' mean chord sag, so chords
  /// straddle a convex target (0 keeps them on the target; 0.5 balances vertex and mid-edge
  /// errors on a sphere).
  double vertex_offset_factor = 0.6;
  bool match_volume = true; ///< correct the patches' central bumps so the volume equals the target's
};

/// How well a patch surface matches the source it was fitted to: the distance of the surface to
/// the source boundary (the target's own zero level, not a mesh of it), over the surface's sample
/// points (mean, 95th percentile, maximum), and the volume error. The figures the log and the
/// provenance report.
struct SourceFit {
  int base_triangles = 0;
  double vertex_offset_factor = 0.6; ///< fraction of each vertex's mean chord sag it was moved out by
  double volume_error = 0.0;         ///< (V_fit - V_target) / V_target
  double source_mean_mm = 0.0, source_p95_mm = 0.0, source_max_mm = 0.0;
};

/// A SourceFit and the distances between the surface and a dense mesh of the target (measure_fit):
/// what the fit's convergence tests compare on analytic targets, where the mesh is exact to its
/// sampling. On a target with pieces that the base mesh misses (a label's small islands) the
/// Hausdorff distance measures those pieces, not the fit.
struct PatchFitReport : SourceFit {
  double hausdorff_mm = 0.0; ///< symmetric Hausdorff distance to the target's dense mesh
  double mean_distance_mm = 0.0;
};

/// The boundary of an implicit target as points on it: where its value changes sign along the
/// edges of a cubic lattice over its bounding ball (each crossing located by false position to
/// 1e-4 of the spacing), each with its outward normal. distance() measures a point's distance to
/// the boundary against these points: to the nearest one, or to its tangent plane when the point
/// lies within 1.5 spacings of that point's normal line (a curved boundary between lattice
/// crossings), within about spacing^2 x curvature. Features thinner than the spacing may be
/// missed; the spacing is at most 1 mm for targets of up to 200 mm radius.
class TargetBoundary {
public:
  /// @param spacing_mm the lattice spacing; 0: min(1 mm, radius / 32), at least radius / 200
  explicit TargetBoundary(const ImplicitShape& target, double spacing_mm = 0.0);
  double distance(const Eigen::Vector3d& x) const;
  std::size_t point_count() const { return m_points.size(); }
  double spacing_mm() const { return m_spacing; }

private:
  std::vector<Eigen::Vector3d> m_points, m_normals;
  double m_spacing = 1.0, m_cell = 2.0;
  Eigen::Vector3d m_origin = Eigen::Vector3d::Zero();
  Eigen::Vector3i m_cells = Eigen::Vector3i::Ones();
  std::vector<std::uint32_t> m_first, m_order; ///< points per hash cell (compressed rows)
};

/// The icosphere base mesh of a star-shaped target: vertices on the target along rays from its
/// centre, through an ellipsoid-shaped icosphere of the target's extent.
/// @param radii_hint semi-axes used to spread the vertices (e.g. the target's radii)
/// @param rotation the target's frame
TriangleMesh target_base_mesh(const ImplicitShape& target, int base_triangles,
                              const Eigen::Vector3d& radii_hint, const Eigen::Matrix3d& rotation);

/// The base mesh of any closed target: its surface extracted and meshed with about
/// `base_triangles` triangles, vertices on the target (anatomy/surface_extraction.hpp).
TriangleMesh surface_base_mesh(const ImplicitShape& target, int base_triangles, std::uint32_t seed);

/// The base mesh a fit with these options uses (BaseMeshSource::automatic resolved).
TriangleMesh fit_base_mesh(const ImplicitShape& target, const PatchFitOptions& options,
                           const Eigen::Vector3d& radii_hint, const Eigen::Matrix3d& rotation);

/// Fits the bump amplitudes of every patch to the target by linear least squares (heights of the
/// target along each patch's normal at interior sample points).
void fit_bumps(PatchSurface& surface, const ImplicitShape& target, const PatchFitOptions& options);

/// Adds the same amplitude to the first bump of every patch so the enclosed volume equals
/// `target_volume` (mm^3); patches without bumps are left alone.
void match_volume(PatchSurface& surface, double target_volume);

/// Moves base vertices outward along the target normal by `factor` times the mean depth of their
/// edges' chord midpoints below the target, so that chords straddle a convex target (and sink
/// into a concave one). The depth is taken along the ray from the centre on star-shaped
/// targets, and along the mean of the two end points' normals, within half the edge's length, on
/// others (so a fold's other sheet is not taken for the edge's own).
Eigen::MatrixX3d straddle_vertices(const TriangleMesh& base, const ImplicitShape& target, double factor);

/// Builds a fitted patch surface: base mesh, vertex placement, bumps, and a volume correction
/// spread over the central bump of every patch. The report measures star-shaped targets
/// within 1e-3 bounding_radius() on 20 * 4^6 target samples, others within
/// 0.1 edge^2 / bounding_radius() on 20 * 4^5 (see measure_fit).
PatchSurface fit_patch_surface(const ImplicitShape& target, const Eigen::Vector3d& radii_hint,
                               const Eigen::Matrix3d& rotation, const PatchFitOptions& options,
                               const std::string& what, PatchFitReport* report = nullptr);

/// Measures a surface against its source: the distance of exact surface points (each patch's
/// grid of surface_sample_level: 2^level segments per edge) to the target's own boundary
/// (TargetBoundary: mean, 95th percentile, maximum) and the volume error.
SourceFit measure_source_fit(const PatchSurface& surface, const ImplicitShape& target,
                             int surface_sample_level = 4);

/// measure_source_fit, and the Hausdorff and mean distance between the same surface points and
/// the target as a dense mesh of 20 * 4^target_sample_level triangles with vertices on it (an
/// icosphere cast from the centre of a star-shaped target, the extracted surface of any other),
/// and from those target points to a tessellation within `tessellation_mm`.
PatchFitReport measure_fit(const PatchSurface& surface, const ImplicitShape& target, double tessellation_mm,
                           int target_sample_level = 6, int surface_sample_level = 4);

/// The surface_sample_level of measure_fit that samples a surface about every `spacing_mm`
/// (patch edges of mean length L get 2^level >= L / spacing_mm segments), from 1 to 4: a base
/// mesh of many small patches is measured at the density of a coarse one, not 16 times per edge.
int surface_sample_level_for_spacing(const PatchSurface& surface, double spacing_mm);

} // namespace phantasm
