// The metrics of a registration evaluation: displacement fields in the ITK/elastix
// convention, warping of labels and points, Dice, Hausdorff distances and Jacobian statistics.
#pragma once

#include "core/grid.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// A displacement field in the ITK/elastix convention (docs/architecture.md, units and frames):
/// on a fixed grid, components in world LPS mm, a fixed point x lands at x + u(x) in the moving
/// image.
struct DisplacementField {
  ImageGrid grid;
  std::vector<Eigen::Vector3d> lps_mm; ///< grid.voxel_count(), i fastest

  /// u at a world (RAS mm) position, trilinear between voxel centres, clamped at the border.
  Eigen::Vector3d at(const Eigen::Vector3d& ras_mm) const;
  /// Where a world (RAS mm) position lands: ras + u, u turned from LPS into RAS.
  Eigen::Vector3d moved(const Eigen::Vector3d& ras_mm) const;
};

/// Reads a 5-D displacement field (phantasm's own, or elastix/transformix `-def` output).
/// @throws InputError naming the file for another layout
DisplacementField read_displacement_field(const std::filesystem::path& path);

/// The identity: zero displacement on `grid`.
DisplacementField zero_field(const ImageGrid& grid);

/// Mean, standard deviation, 95th percentile (linear between order statistics) and maximum.
struct Summary {
  std::size_t count = 0;
  double mean = 0.0, sd = 0.0, p95 = 0.0, max = 0.0;
};
Summary summarize(std::vector<double> values);

/// The summary of one structure's values (an organ's dense landmarks' TRE).
struct StructureSummary {
  std::string structure;
  Summary summary;
};
/// Values grouped by structure (structures[i] names values[i]'s), one summary per structure in
/// the order the structures first appear.
std::vector<StructureSummary> summarize_by_structure(const std::vector<std::string>& structures,
                                                     const std::vector<double>& values);

/// Resamples a moving label map onto the fixed grid of `field`: each fixed voxel takes the label
/// of the moving voxel nearest to x + u(x) (0 outside the moving grid).
std::vector<std::int32_t> warp_labels(const std::vector<std::int32_t>& moving, const ImageGrid& moving_grid,
                                      const DisplacementField& field);

/// Overlap of one label between the fixed labels and a warped moving label map.
struct LabelOverlap {
  std::int32_t label = 0;
  std::int64_t fixed_voxels = 0, warped_voxels = 0;
  double dice = 0.0;
  /// 95th percentile Hausdorff distance (mm) between the two label surfaces (voxels of the label
  /// with a face neighbour outside it): the larger of the two directed 95th percentiles.
  /// Infinity when one side has no voxel of the label.
  double hd95_mm = 0.0;
};
LabelOverlap label_overlap(const std::vector<std::int32_t>& fixed, const std::vector<std::int32_t>& warped,
                           const ImageGrid& grid, std::int32_t label);

/// det(I + grad u) of a field over a region, with the gradient in world coordinates (central
/// differences, one-sided at the border). Folding (det <= 0) is counted on the raw determinants;
/// the log is then taken of determinants clipped to [1e-9, 1e9].
struct JacobianStatistics {
  std::int64_t voxels = 0, folding_voxels = 0;
  double folding_fraction = 0.0, log_jacobian_sd = 0.0, min_determinant = 0.0, max_determinant = 0.0;
};
JacobianStatistics jacobian_statistics(const DisplacementField& field, const std::vector<bool>& region);

} // namespace phantasm
