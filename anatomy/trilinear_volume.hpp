// A box of voxel values sampled trilinearly between their centres, 0 outside the box: a label
// volume's smoothed indicator (anatomy/file_shapes.cpp, make_label_shape). In a header so that the
// patch fit's height searches, which sample it hundreds of millions of times, call it inline.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace phantasm {

class TrilinearVolume {
public:
  /// The box of `dims` voxels from voxel `low` of a volume whose voxel (i, j, k) lies at
  /// world_from_voxel (i, j, k, 1); values by local_index(), zeros until set.
  TrilinearVolume(const Eigen::Matrix4d& world_from_voxel, const Eigen::Vector3i& low,
                  const Eigen::Vector3i& dims);

  /// The interpolated value at world point x, minus 1/2 (a smoothed indicator's surface is 0).
  double value(const Eigen::Vector3d& x) const {
    // On a grid whose axes are the world's (the atlases, most scans), the matrix's other terms
    // are zeros, which add nothing: the same bits for a third of the work.
    const Eigen::Vector3d ijk =
        m_axis_aligned ? Eigen::Vector3d(m_voxel_from_world(0, 0) * (x.x() - m_origin.x()) - m_low_d.x(),
                                         m_voxel_from_world(1, 1) * (x.y() - m_origin.y()) - m_low_d.y(),
                                         m_voxel_from_world(2, 2) * (x.z() - m_origin.z()) - m_low_d.z())
                       : Eigen::Vector3d(m_voxel_from_world * (x - m_origin) - m_low_d);
    // A cell inside the box: 0 <= ijk < dims - 1 (so floor(ijk) + 1 < dims), where truncation is
    // the floor.
    if (!(ijk.x() >= 0.0 && ijk.y() >= 0.0 && ijk.z() >= 0.0 && ijk.x() < m_last_cell.x() &&
          ijk.y() < m_last_cell.y() && ijk.z() < m_last_cell.z()))
      return value_near_edge(ijk);
    const Eigen::Vector3i at(static_cast<int>(ijk.x()), static_cast<int>(ijk.y()), static_cast<int>(ijk.z()));
    const Eigen::Vector3d base = at.cast<double>();
    // The cell lies in the box: its eight values, weighted as value_near_edge weights them (the
    // same products in the same order, so the same bits), without a bounds test per corner.
    const Eigen::Vector3d t = ijk - base;
    const float* cell = m_values.data() + local_index(at);
    const std::ptrdiff_t dy = m_dims.x(), dz = std::ptrdiff_t{m_dims.x()} * m_dims.y();
    const double wx[2] = {1.0 - t.x(), t.x()}, wy[2] = {1.0 - t.y(), t.y()}, wz[2] = {1.0 - t.z(), t.z()};
    double total = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const int ox = corner & 1, oy = (corner >> 1) & 1, oz = (corner >> 2) & 1;
      total += wx[ox] * wy[oy] * wz[oz] * cell[ox + oy * dy + oz * dz];
    }
    return total - 0.5;
  }

  std::size_t local_index(const Eigen::Vector3i& at) const {
    return static_cast<std::size_t>((std::int64_t{at.z()} * m_dims.y() + at.y()) * m_dims.x() + at.x());
  }
  const Eigen::Matrix3d& voxel_from_world() const { return m_voxel_from_world; }
  std::vector<float>& values() { return m_values; }
  const std::vector<float>& values() const { return m_values; }

private:
  /// value() at a point whose cell reaches past the box: corners outside it count as 0.
  double value_near_edge(const Eigen::Vector3d& ijk) const;

  Eigen::Matrix3d m_voxel_from_world = Eigen::Matrix3d::Identity();
  bool m_axis_aligned = true;           ///< m_voxel_from_world is diagonal
  Eigen::Vector3d m_low_d{0, 0, 0};     ///< the box's first voxel in the volume, as doubles
  Eigen::Vector3d m_last_cell{0, 0, 0}; ///< m_dims - 1 as doubles: the cells' lower corners lie below
  Eigen::Vector3d m_origin{0, 0, 0};
  Eigen::Vector3i m_dims{0, 0, 0}; ///< the box's size in voxels
  std::vector<float> m_values;     ///< by local_index()
};

} // namespace phantasm
