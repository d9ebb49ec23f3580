// The out-of-line parts of TrilinearVolume: its affine, and the samples at the box's edge.
#include "anatomy/trilinear_volume.hpp"

#include <Eigen/LU>

namespace phantasm {

TrilinearVolume::TrilinearVolume(const Eigen::Matrix4d& world_from_voxel, const Eigen::Vector3i& low,
                                 const Eigen::Vector3i& dims)
    : m_low_d(low.cast<double>()), m_last_cell((dims - Eigen::Vector3i::Ones()).cast<double>()), m_dims(dims),
      m_values(static_cast<std::size_t>(dims.cast<std::int64_t>().prod()), 0.0f) {
  // value() runs millions of times while meshing: invert the affine once.
  m_voxel_from_world = world_from_voxel.topLeftCorner<3, 3>().inverse();
  m_origin = world_from_voxel.topRightCorner<3, 1>();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      m_axis_aligned = m_axis_aligned && (r == c || m_voxel_from_world(r, c) == 0.0);
}

double TrilinearVolume::value_near_edge(const Eigen::Vector3d& ijk) const {
  const Eigen::Vector3d base = ijk.array().floor();
  double total = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    double weight = 1.0;
    Eigen::Vector3i at;
    for (int a = 0; a < 3; ++a) {
      const int offset = (corner >> a) & 1;
      at[a] = static_cast<int>(base[a]) + offset;
      const double t = ijk[a] - base[a];
      weight *= offset ? t : 1.0 - t;
    }
    if ((at.array() < 0).any() || (at.array() >= m_dims.array()).any() || weight == 0.0) continue;
    total += weight * m_values[local_index(at)];
  }
  return total - 0.5;
}

} // namespace phantasm
