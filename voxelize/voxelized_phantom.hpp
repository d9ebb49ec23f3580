// The voxelization's result: labels and tissue fractions on the image grid, the motion
// fields and landmarks, read by the MR stage and the writers without OpenVDB.
#pragma once

#include "core/grid.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
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

/// Labels and partial-volume fractions on an image grid. Most voxels lie wholly in one organ (or
/// in none): their fractions follow from the label, 1 for the label's tissue and 0 for every
/// other tissue and the background. Only the other voxels, near the surfaces (a few per cent of
/// the grid), store their fractions: a dense float per tissue and voxel would hold most of a run's
/// memory (docs/volumes-and-images.md, "How the fractions are held").
struct TissueVolumes {
  std::vector<std::int32_t> labels; ///< voxel_count(): the organ (dseg index) of the largest fraction, 0
                                    ///< background, organs + 1 the gap
  /// Per label value, every value in `labels` included (0 always): the tissue (index into the
  /// tissue list) that fills a voxel of that label whole, -1 for none (0, background; a gap of air).
  std::vector<int> label_tissues;
  int tissue_count = 0;
  /// The voxels whose fractions are not their label's alone, ascending.
  std::vector<std::size_t> partial_voxels;
  /// Per partial voxel, in the same order: tissue_count fractions, then the background's
  /// (fractions_per_voxel() floats). With background they sum to 1.
  std::vector<float> partial_fractions;
  std::size_t supersampled_voxels = 0; ///< voxels near a surface sampled by this pass (not those
                                       ///< copied from the other state)

  /// Floats per voxel in partial_fractions and in what for_each_voxel() passes: every tissue's,
  /// then the background's.
  std::size_t fractions_per_voxel() const { return static_cast<std::size_t>(tissue_count) + 1; }

  /// Which of a whole voxel's fractions_per_voxel() floats is 1 for `label`: its tissue, or
  /// tissue_count (the background) for a label without one.
  std::size_t filled_by(std::int32_t label) const {
    const int tissue = label_tissues[static_cast<std::size_t>(label)];
    return static_cast<std::size_t>(tissue < 0 ? tissue_count : tissue);
  }
  /// Whether `fractions` (fractions_per_voxel() floats) are, bit for bit, those a voxel of
  /// `label` has when it is whole, so that they need not be stored.
  bool whole(std::int32_t label, const float* fractions) const {
    const std::size_t filled = filled_by(label);
    for (std::size_t t = 0; t < fractions_per_voxel(); ++t)
      if (fractions[t] != (t == filled ? 1.0f : 0.0f) || std::signbit(fractions[t])) return false;
    return true;
  }
  /// Appends `voxel` (beyond every voxel appended before) to the partial voxels with its
  /// fractions (fractions_per_voxel() floats) unless they are its label's alone.
  void add_voxel_fractions(std::size_t voxel, const float* fractions) {
    if (whole(labels[voxel], fractions)) return;
    partial_voxels.push_back(voxel);
    partial_fractions.insert(partial_fractions.end(), fractions, fractions + fractions_per_voxel());
  }

  /// The fraction of `tissue` (tissue_count: the background) in `voxel`.
  float fraction(int tissue, std::size_t voxel) const {
    const auto found = std::lower_bound(partial_voxels.begin(), partial_voxels.end(), voxel);
    if (found != partial_voxels.end() && *found == voxel)
      return partial_fractions[static_cast<std::size_t>(found - partial_voxels.begin()) *
                                   fractions_per_voxel() +
                               static_cast<std::size_t>(tissue)];
    return filled_by(labels[voxel]) == static_cast<std::size_t>(tissue) ? 1.0f : 0.0f;
  }
  /// The background's fraction in `voxel`: outside every organ, or in a gap of air.
  float background(std::size_t voxel) const { return fraction(tissue_count, voxel); }

  /// Calls visit(voxel, fractions) for every voxel of [first, last) in order, `fractions`
  /// pointing to fractions_per_voxel() floats (every tissue's, then the background's): the
  /// stored ones of a partial voxel, those of its label otherwise.
  template <typename Visit>
  void for_each_voxel(std::size_t first, std::size_t last, Visit&& visit) const {
    const std::size_t stride = fractions_per_voxel();
    std::vector<float> whole(label_tissues.size() * stride, 0.0f); // per label: its voxels' fractions
    for (std::size_t label = 0; label < label_tissues.size(); ++label)
      whole[label * stride + filled_by(static_cast<std::int32_t>(label))] = 1.0f;
    auto partial = std::lower_bound(partial_voxels.begin(), partial_voxels.end(), first);
    for (std::size_t voxel = first; voxel < last; ++voxel) {
      if (partial != partial_voxels.end() && *partial == voxel) {
        visit(voxel, &partial_fractions[static_cast<std::size_t>(partial - partial_voxels.begin()) * stride]);
        ++partial;
      } else {
        visit(voxel, &whole[static_cast<std::size_t>(labels[voxel]) * stride]);
      }
    }
  }

  /// The sum of one tissue's fraction (tissue_count: the background's) over the voxels, in
  /// voxel order: its volume in voxels.
  double fraction_sum(int tissue) const {
    double sum = 0.0;
    for_each_voxel(0, labels.size(), [&](std::size_t, const float* fractions) {
      sum += fractions[static_cast<std::size_t>(tissue)];
    });
    return sum;
  }

  /// One tissue's fraction (tissue_count: the background's) in every voxel, as a dense volume
  /// (what the writers write).
  std::vector<float> fraction_volume(int tissue) const {
    std::vector<float> volume(labels.size());
    for_each_voxel(0, labels.size(), [&](std::size_t voxel, const float* fractions) {
      volume[voxel] = fractions[static_cast<std::size_t>(tissue)];
    });
    return volume;
  }
};

/// The TissueVolumes of dense fractions (per tissue, then the background: tissue_count + 1
/// volumes of labels.size() voxels): only the voxels whose fractions are not their label's alone
/// are kept.
inline TissueVolumes compact_tissue_volumes(std::vector<std::int32_t> labels, std::vector<int> label_tissues,
                                            const std::vector<std::vector<float>>& fractions) {
  TissueVolumes out;
  out.labels = std::move(labels);
  out.label_tissues = std::move(label_tissues);
  out.tissue_count = static_cast<int>(fractions.size()) - 1;
  std::vector<float> row(fractions.size());
  for (std::size_t voxel = 0; voxel < out.labels.size(); ++voxel) {
    for (std::size_t t = 0; t < row.size(); ++t)
      row[t] = fractions[t][voxel];
    out.add_voxel_fractions(voxel, row.data());
  }
  return out;
}

/// Dense displacement fields both ways on one grid (RAS mm, x_to = x + u(x)), their exact-masks,
/// and the Jacobian determinant of each. (In the dataset, ref_to_def is the BIDS transform
/// from-def_to-ref, def_to_ref is from-ref_to-def: io/dataset_layout.hpp.)
struct MotionFields {
  std::vector<float> ref_to_def; ///< 3 * voxel_count: component-major (all x, then all y, then all z)
  std::vector<float> def_to_ref;
  std::vector<std::uint8_t> ref_to_def_exact, def_to_ref_exact;
  /// det(I + grad u) of ref_to_def, central differences (one-sided inside the exact mask next to
  /// a voxel outside it, and next to still tissue)
  std::vector<float> jacobian;
  std::vector<float> def_to_ref_jacobian; ///< det(I + grad u) of def_to_ref, likewise
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

/// Spatial variation of T1 and PD within the textured tissues of one state: per voxel, factors
/// of the tissues' T1 and PD (1 where nothing varies), the reference's made in reference space and
/// the deformed state's carried to it by the exact map (voxelize/material_maps.hpp).
struct TextureMaps {
  std::vector<float> T1_factor, PD_factor; ///< voxel_count() each
  std::vector<bool> textured;              ///< per tissue (the phantom's tissue list): the factors apply
  std::string description;                 ///< the source and parameters, for sidecars and provenance
};

/// The volumes of one run: labels and fractions of both states, and the motion between them.
struct VoxelizedPhantom {
  ImageGrid grid;
  std::vector<std::string> tissues; ///< tissue names, in order of first use by an organ
  TissueVolumes reference;
  std::optional<TissueVolumes> deformed;                          ///< when the scene deforms
  std::optional<MotionFields> motion;                             ///< when the scene deforms
  std::optional<TextureMaps> reference_texture, deformed_texture; ///< when the scene asks for texture
  std::vector<Landmark> landmarks; ///< both states (equal when nothing deforms)
  std::vector<Landmark>
      dense_landmarks; ///< seeded material points per organ, both states (dense_landmarks.hpp)
  /// The organs' level sets by organ name, kept when the scene asks for .vdb output. Shared and
  /// opaque, so that holding them needs no OpenVDB (LevelSet::grid() gives the grid to write).
  std::vector<std::pair<std::string, std::shared_ptr<const LevelSet>>> reference_level_sets,
      deformed_level_sets;
};

} // namespace phantasm
