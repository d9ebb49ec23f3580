// Landmarks of the phantom: seven material points per closed organ (deepest point and extreme
// surface points), exact in both states.
#pragma once

#include "anatomy/organ.hpp"
#include "core/grid.hpp"
#include "sim/phantom_deformation.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace phantasm {

/// The reference state's voxel labels on their grid (voxelized_phantom.hpp: organ index + 1, 0
/// for background), in which the deepest points are searched when given.
struct ReferenceLabels {
  const ImageGrid* grid = nullptr;
  const std::vector<std::int32_t>* labels = nullptr;
  /// An organ's depth comes from its label when the label's box holds fewer voxels than this
  /// per bump of the organ's surface [choice]: the distance transform costs about 18 ns per
  /// voxel, the tessellation search about 1-3 us per bump (the procedural head's organs, 8000
  /// bumps in boxes of up to 4.6 million voxels at 1 mm, search their tessellations in 0.07 s
  /// against 0.28 s; the Colin head's, 53 000 to 830 000 bumps, in 2.7 s against 0.6 s).
  /// Infinity: every organ the labels can tell.
  double voxels_per_bump = 200.0;
};

/// Each organ's candidates for its deepest point from the reference labels, by organ index, in
/// the order organ_landmarks tries them: the deepest voxel centre in the organ's own material,
/// then up to 64 more, each a step (a fortieth of the organ's extent) from those after the first.
/// Empty for an organ the labels cannot tell (see organ_landmarks; its depth then comes from the
/// tessellations) and for one without a surface. They depend on the reference phantom and its
/// labels alone, so the reference state keeps them (pipeline/reference_cache.hpp) and each
/// deformation of it picks from them: organ_landmarks given them returns what it returns from the
/// labels, bit for bit, without the distance transforms.
using DeepestCandidates = std::vector<std::vector<Eigen::Vector3d>>;

/// The candidates of every organ (DeepestCandidates) from `labels`.
DeepestCandidates deepest_candidates(const Phantom& reference, const ReferenceLabels& labels);

/// Seven landmarks per closed organ, each a material point of that organ: the deepest point of
/// its own material ("<organ>_deepest": inside it and outside the organs nested in it, farthest
/// from both; with a map, the deepest around which the map is exact for the organ's motion) and
/// its extreme surface points towards left, right, posterior, anterior, inferior and superior
/// (patch base vertices). Both states are exact: an extreme point's deformed position is its
/// vertex's solved one; the deepest point of an organ the solver moved goes through the map
/// (barycentric in the solved tets), that of an organ that did not move stays.
/// The depth is measured one of two ways, and either way the point's side of every surface is
/// exact (from the patches themselves), so the deepest point is a material point of its organ:
/// - with `labels`, for an organ that lies within the grid (none of its or its nested organs'
///   labels on the grid's border; axes orthogonal) and whose surface carries enough bumps for the
///   labels to be the cheaper way (ReferenceLabels::voxels_per_bump): the exact Euclidean
///   distance transform of its
///   own label, so the depth is that of the voxel centres, known to within a voxel; the point is
///   the centre of the deepest voxel whose centre lies in the organ's own material;
/// - otherwise (no labels, an organ the grid cuts or misses, a simple surface in a large box, or
///   one whose labelled voxels have no centre in its material: thinner than a voxel): distances
///   to its surfaces tessellated within
///   `depth_tolerance_mm`, over a grid of candidates and rays inward from the base vertices,
///   refined by a compass search. Tessellating the folded Colin white matter within 0.5 mm makes
///   5 million triangles, within 1 mm 1.8 million: seconds per organ.
/// An organ whose own material holds no point (the organs nested in it fill it) has no deepest
/// point: that landmark is left out, with a warning.
/// @param map the reference-to-deformed map (nullptr without a deformation)
/// @param depth_tolerance_mm the tessellations' tolerance, mm (voxelize_phantom passes the voxel
///        edge, 0.5-2 mm)
/// @param warnings receives a line per landmark left out (nullptr: none kept)
/// @param organ_done called after each organ with a surface (a progress step; empty: none)
/// @param labels the reference labels (none: every depth from the tessellations)
/// @param candidates deepest_candidates() of these labels, when known: then the labels are not
///        read again (the same landmarks)
std::vector<Landmark> organ_landmarks(const Phantom& reference, const PhantomDeformation* deformation,
                                      const DeformationMap* map, double depth_tolerance_mm,
                                      std::vector<std::string>* warnings = nullptr,
                                      const std::function<void()>& organ_done = {},
                                      const ReferenceLabels& labels = {},
                                      const DeepestCandidates* candidates = nullptr);

/// Whether points lie in an organ's own material: inside its surface and outside the organs
/// nested in it, each side decided from the patches as the voxelizer decides it (the closest base
/// triangle, its pseudonormals, then the height of the patch's bumps), so exact whatever a
/// tessellation would show. The test organ_landmarks() makes of its deepest points.
class OrganMaterial {
public:
  /// @param organ index of a closed organ (one with a surface) in phantom.organs
  OrganMaterial(const Phantom& phantom, std::size_t organ);
  ~OrganMaterial();
  OrganMaterial(OrganMaterial&&) noexcept;

  /// Whether x (RAS mm) lies in the organ's own material. Not for several threads at once (it
  /// keeps the last point's closest triangles to start the next search from).
  bool contains(const Eigen::Vector3d& x);

private:
  struct Sides;
  std::unique_ptr<Sides> m_sides;
};

/// CSV text of one state: "name,organ,x_mm,y_mm,z_mm" (world RAS mm), one landmark per line.
std::string landmarks_csv(const std::vector<Landmark>& landmarks, bool deformed);

} // namespace phantasm
