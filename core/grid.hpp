// ImageGrid, a voxel grid placed in world space (RAS mm, NIfTI's voxel order), and the linear
// index of a voxel: the grid every volume, image and field of a run lives on.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace phantasm {

/// A regular voxel grid placed in world space (RAS+, millimetres). Voxel centres sit at integer
/// indices (i, j, k), as in NIfTI: world = world_from_voxel * (i, j, k, 1).
struct ImageGrid {
  Eigen::Vector3i dims{0, 0, 0};                                  ///< voxels along i, j, k
  Eigen::Vector3d spacing_mm{1.0, 1.0, 1.0};                      ///< voxel size along i, j, k, in mm
  Eigen::Matrix4d world_from_voxel = Eigen::Matrix4d::Identity(); ///< RAS mm from voxel index

  /// World position (RAS mm) of a continuous voxel index.
  Eigen::Vector3d world_from_index(const Eigen::Vector3d& ijk) const;
  /// Continuous voxel index of a world position (RAS mm).
  Eigen::Vector3d index_from_world(const Eigen::Vector3d& ras_mm) const;
  /// Number of voxels, dims.prod() without overflow.
  std::int64_t voxel_count() const;
};

/// ImageGrid::index_from_world with the grid's inverse made once, for loops over many points:
/// the same arithmetic, so the same values, without a 3 x 3 inverse per point.
class IndexFromWorld {
public:
  explicit IndexFromWorld(const ImageGrid& grid);
  /// Continuous voxel index of a world position (RAS mm).
  Eigen::Vector3d operator()(const Eigen::Vector3d& ras_mm) const { return m_inverse * (ras_mm - m_origin); }

private:
  Eigen::Matrix3d m_inverse;
  Eigen::Vector3d m_origin;
};

/// Linear index of voxel (i, j, k) in an array stored with i fastest, then j, then k (NIfTI's
/// order, the layout of every volume here): i + dims.x (j + dims.y k).
/// @param dims voxels along i, j, k
/// @param i, j, k voxel index, each in [0, dims)
inline std::size_t voxel_index(const Eigen::Vector3i& dims, int i, int j, int k) {
  return static_cast<std::size_t>(i) +
         static_cast<std::size_t>(dims.x()) *
             (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims.y()) * static_cast<std::size_t>(k));
}

/// Direction cosines for a three-letter axis code such as "RAS" or "LPI". Each letter names the
/// world direction in which its voxel index increases (nibabel's convention): "RAS" is the
/// identity, "LPS" negates the first two axes. Column c of the result is the world direction of
/// index axis c. Returns nothing when the code is not a permutation of one letter from each of
/// R/L, A/P, S/I.
std::optional<Eigen::Matrix3d> direction_from_axis_code(const std::string& code);

/// The grid that covers a field of view centred at center_mm.
/// @param field_of_view_mm extent along each index axis, in mm
/// @param voxel_size_mm voxel size along each index axis, in mm (positive)
/// @param center_mm world position (RAS mm) of the centre of the field of view
/// @param direction direction cosines from direction_from_axis_code()
/// The number of voxels along an axis is round(field_of_view / voxel_size), at least 1.
ImageGrid make_centered_grid(const Eigen::Vector3d& field_of_view_mm, const Eigen::Vector3d& voxel_size_mm,
                             const Eigen::Vector3d& center_mm, const Eigen::Matrix3d& direction);

/// The largest prime factor of a grid size n (1 for n <= 1): a transform along an axis is fast
/// when it is small (FFTW has fast algorithms for the primes up to 13).
int largest_prime_factor(int n);

/// The imaging grid of a scene (docs/scene-format.md, section grid): where voxelize samples the
/// phantom and mri makes its images.
struct GridSettings {
  Eigen::Vector3d field_of_view_mm{256, 256, 256}; ///< extent along i, j, k in mm
  Eigen::Vector3d voxel_size_mm{1, 1, 1};          ///< voxel size along i, j, k in mm
  Eigen::Vector3d center_mm{0, 0, 0};              ///< RAS mm position of the grid centre
  std::string orientation = "RAS";                 ///< axis code, see direction_from_axis_code()

  ImageGrid grid() const;
};

} // namespace phantasm
