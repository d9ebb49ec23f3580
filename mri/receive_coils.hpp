// Receive coil sensitivities: a ring of coils around the object with a Biot-Savart falloff and
// smooth phase, normalized so a sum-of-squares image keeps the one-coil scale.
#pragma once

#include "core/grid.hpp"

#include <complex>
#include <vector>

namespace phantasm {

/// Receive sensitivities of a ring of coils around the object: `count` long conductors parallel
/// to the grid's third axis, evenly spaced on a circle of radius 0.6 x the larger in-plane field
/// of view about the grid's centre. Coil c at angle theta_c sees a voxel at in-plane distance d
/// and direction phi from it with sensitivity (r / d) exp(i (phi + theta_c)), a two-dimensional
/// Biot-Savart falloff with a smooth phase. The maps are scaled so that the root sum of squares
/// of the sensitivities averages 1 over the object: a sum-of-squares image keeps the scale of a
/// one-coil image and shows the brighter periphery that receive arrays give. One coil is a
/// uniform body coil (sensitivity 1).
class ReceiveCoils {
public:
  /// @param object_mask voxel_count() flags of the voxels that hold tissue (normalization)
  ReceiveCoils(const ImageGrid& grid, int count, const std::vector<bool>& object_mask);

  int count() const { return m_count; }
  /// Sensitivity of coil `coil` at in-plane voxel (i, j) (the same on every slice).
  std::complex<double> sensitivity(int coil, int i, int j) const {
    return m_count == 1 ? std::complex<double>(1.0) : m_planes[static_cast<std::size_t>(coil)][index(i, j)];
  }
  /// Coil `coil`'s in-plane sensitivities (nx x ny, x fastest), or nullptr for the uniform body coil.
  const std::complex<double>* sensitivity_plane(int coil) const {
    return m_count == 1 ? nullptr : m_planes[static_cast<std::size_t>(coil)].data();
  }
  /// Root sum of squares of all coils' sensitivities at in-plane voxel (i, j).
  double root_sum_of_squares(int i, int j) const;

private:
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * m_nx + static_cast<std::size_t>(i);
  }
  int m_count;
  std::size_t m_nx;
  std::vector<std::vector<std::complex<double>>> m_planes; ///< per coil, nx * ny
};

} // namespace phantasm
