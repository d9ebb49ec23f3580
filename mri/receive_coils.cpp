#include "mri/receive_coils.hpp"

#include <cmath>

namespace phantasm {

ReceiveCoils::ReceiveCoils(const ImageGrid& grid, int count, const std::vector<bool>& object_mask)
    : m_count(count), m_nx(static_cast<std::size_t>(grid.dims.x())) {
  if (count <= 1) {
    m_count = 1;
    return;
  }
  const int nx = grid.dims.x(), ny = grid.dims.y();
  const double radius = 0.6 * std::max(nx * grid.spacing_mm.x(), ny * grid.spacing_mm.y());
  m_planes.assign(
      static_cast<std::size_t>(count),
      std::vector<std::complex<double>>(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny)));
  for (int c = 0; c < count; ++c) {
    const double theta = 2.0 * M_PI * c / count;
    const double cx = radius * std::cos(theta), cy = radius * std::sin(theta);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const double x = (i - 0.5 * (nx - 1)) * grid.spacing_mm.x() - cx;
        const double y = (j - 0.5 * (ny - 1)) * grid.spacing_mm.y() - cy;
        // The clamp keeps field-of-view corners beyond the ring finite.
        const double distance = std::max(std::hypot(x, y), 0.05 * radius);
        m_planes[static_cast<std::size_t>(c)][index(i, j)] =
            std::polar(radius / distance, std::atan2(y, x) + theta);
      }
    }
  }
  // Scale: the root sum of squares averages 1 over the object (over the whole grid without one).
  // The in-plane roots once, not once per voxel of the object; added in voxel order.
  const std::size_t plane = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::vector<double> root(plane);
  for (std::size_t p = 0; p < plane; ++p)
    root[p] = root_sum_of_squares(static_cast<int>(p % m_nx), static_cast<int>(p / m_nx));
  double sum = 0.0, voxels = 0.0;
  for (std::size_t v = 0, p = 0; v < object_mask.size(); ++v, ++p) {
    if (p == plane) p = 0;
    if (!object_mask[v]) continue;
    sum += root[p];
    voxels += 1.0;
  }
  if (voxels == 0.0) {
    for (std::size_t p = 0; p < plane; ++p)
      sum += root[p];
    voxels = static_cast<double>(plane);
  }
  const double scale = voxels / sum;
  for (auto& coil : m_planes)
    for (auto& s : coil)
      s *= scale;
}

double ReceiveCoils::root_sum_of_squares(int i, int j) const {
  if (m_count == 1) return 1.0;
  double sum = 0.0;
  for (const auto& coil : m_planes)
    sum += std::norm(coil[index(i, j)]);
  return std::sqrt(sum);
}

} // namespace phantasm
