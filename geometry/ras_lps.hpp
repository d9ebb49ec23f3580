// RAS+ (NIfTI, phantasm's world) and LPS+ (ITK, DICOM, elastix) world coordinates: the same
// millimetres with x and y negated, for points, displacement vectors and component arrays alike.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace phantasm {

/// The map between RAS and LPS coordinates, its own inverse: diag(-1, -1, 1).
inline Eigen::DiagonalMatrix<double, 3> ras_lps_flip() {
  return Eigen::DiagonalMatrix<double, 3>(-1.0, -1.0, 1.0);
}

/// LPS coordinates (mm) of a point or vector given in RAS (mm).
inline Eigen::Vector3d lps_from_ras(const Eigen::Vector3d& ras) {
  return {-ras.x(), -ras.y(), ras.z()};
}

/// RAS coordinates (mm) of a point or vector given in LPS (mm).
inline Eigen::Vector3d ras_from_lps(const Eigen::Vector3d& lps) {
  return {-lps.x(), -lps.y(), lps.z()};
}

/// Converts a vector field stored component-major (all x, then all y, then all z: 3 * voxel
/// count values, as NIfTI stores vectors) between RAS and LPS in place (either way: the
/// conversion is its own inverse).
/// @param components (3 * N) values, mm
inline void flip_ras_lps_components(std::vector<float>& components) {
  const std::size_t count = components.size() / 3;
  for (std::size_t v = 0; v < 2 * count; ++v)
    components[v] = -components[v];
}

/// A component-major vector field (3 * N values, mm) given in RAS, in LPS (or the other way).
inline std::vector<float> lps_from_ras_components(std::vector<float> ras) {
  flip_ras_lps_components(ras);
  return ras;
}

} // namespace phantasm
