// The voxelization's result: labels and tissue fractions on the image grid, the motion
// fields and landmarks, read by the MR stage and the writers without OpenVDB.
#pragma once

#include "core/grid.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

// The voxelization's result types, apart from the voxelizer: plain volumes on an image grid that
// need neither OpenVDB nor the solver, so that the MR stage and the writers read them without
// linking either (target phantasm::voxel_volumes).

namespace phantasm {

class LevelSet; // voxelize/level_set.hpp (OpenVDB), held here only through a pointer

/// The label table's name (dseg.tsv) of the gap: the space a moved organ leaves inside a
/// container that stays, deformed state only (docs/volumes-and-images.md, "The gap"). Its index
/// follows the organs'.
inline constexpr const char* k_gap_label_name = "gap";

/// Labels and partial-volume fractions on an image grid.
struct TissueVolumes {
  std::vector<std::int32_t> labels; ///< voxel_count(): the organ (dseg index) of the largest fraction, 0
                                    ///< background, organs + 1 the gap
  std::vector<std::vector<float>> fractions; ///< per tissue, voxel_count(); with background they sum to 1
  std::vector<float> background;             ///< voxel_count()
  std::size_t supersampled_voxels = 0;       ///< voxels near a surface sampled by this pass (not those
                                             ///< copied from the other state)
};

/// Dense displacement fields both ways on one grid (RAS mm, x_to = x + u(x)), their exact-masks,
/// and the Jacobian determinant of each. (In the dataset, ref_to_def is the BIDS transform
/// from-def_to-ref, def_to_ref is from-ref_to-def: io/dataset_layout.hpp.)
struct MotionFields {
  std::vector<float> ref_to_def; ///< 3 * voxel_count: component-major (all x, then all y, then all z)
  std::vector<float> def_to_ref;
  std::vector<std::uint8_t> ref_to_def_exact, def_to_ref_exact;
  std::vector<float> jacobian;            ///< det(I + grad u) of ref_to_def, central differences
  std::vector<float> def_to_ref_jacobian; ///< det(I + grad u) of def_to_ref, central differences
  double max_displacement_mm = 0.0;
  double min_jacobian = 1.0;
  /// voxels the maps mark exact whose two-way composition misses identity by more than
  /// composition_tolerance_voxels (left out of the masks)
  long inconsistent_voxels = 0;
  /// the largest miss of identity, mm, over the voxels left in the masks
  double max_composition_error_mm = 0.0;
  /// voxels inside the ref_to_def exact mask with a Jacobian <= 0 (a fold: no physical map)
  long folded_exact_voxels = 0;
  double min_exact_jacobian = 1.0; ///< the smallest Jacobian inside the ref_to_def exact mask
};

/// A named anatomical point of an organ, in both states (RAS mm).
struct Landmark {
  std::string name; ///< e.g. "grey_matter_superior"
  std::string organ;
  Eigen::Vector3d reference_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d deformed_mm = Eigen::Vector3d::Zero();
};

/// The volumes of one run: labels and fractions of both states, and the motion between them.
struct VoxelizedPhantom {
  ImageGrid grid;
  std::vector<std::string> tissues; ///< tissue names, in order of first use by an organ
  TissueVolumes reference;
  std::optional<TissueVolumes> deformed; ///< when the scene deforms
  std::optional<MotionFields> motion;    ///< when the scene deforms
  std::vector<Landmark> landmarks;       ///< both states (equal when nothing deforms)
  /// The organs' level sets by organ name, kept when the scene asks for .vdb output. Shared and
  /// opaque, so that holding them needs no OpenVDB (LevelSet::grid() gives the grid to write).
  std::vector<std::pair<std::string, std::shared_ptr<const LevelSet>>> reference_level_sets,
      deformed_level_sets;
};

} // namespace phantasm
