#include "core/grid.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace phantasm {

Eigen::Vector3d ImageGrid::world_from_index(const Eigen::Vector3d& ijk) const {
  return world_from_voxel.topLeftCorner<3, 3>() * ijk + world_from_voxel.topRightCorner<3, 1>();
}

Eigen::Vector3d ImageGrid::index_from_world(const Eigen::Vector3d& ras_mm) const {
  return IndexFromWorld(*this)(ras_mm);
}

IndexFromWorld::IndexFromWorld(const ImageGrid& grid)
    : m_inverse(Eigen::Matrix3d(grid.world_from_voxel.topLeftCorner<3, 3>()).inverse()),
      m_origin(grid.world_from_voxel.topRightCorner<3, 1>()) {}

std::int64_t ImageGrid::voxel_count() const {
  return std::int64_t{dims.x()} * std::int64_t{dims.y()} * std::int64_t{dims.z()};
}

std::optional<Eigen::Matrix3d> direction_from_axis_code(const std::string& code) {
  if (code.size() != 3) return std::nullopt;
  Eigen::Matrix3d direction = Eigen::Matrix3d::Zero();
  bool used[3] = {false, false, false};
  for (int column = 0; column < 3; ++column) {
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(code[column])));
    int world_axis = -1;
    double sign = 1.0;
    switch (letter) {
    case 'R': world_axis = 0; break;
    case 'L':
      world_axis = 0;
      sign = -1.0;
      break;
    case 'A': world_axis = 1; break;
    case 'P':
      world_axis = 1;
      sign = -1.0;
      break;
    case 'S': world_axis = 2; break;
    case 'I':
      world_axis = 2;
      sign = -1.0;
      break;
    default: return std::nullopt;
    }
    if (used[world_axis]) return std::nullopt;
    used[world_axis] = true;
    direction(world_axis, column) = sign;
  }
  return direction;
}

ImageGrid make_centered_grid(const Eigen::Vector3d& field_of_view_mm, const Eigen::Vector3d& voxel_size_mm,
                             const Eigen::Vector3d& center_mm, const Eigen::Matrix3d& direction) {
  ImageGrid grid;
  grid.spacing_mm = voxel_size_mm;
  for (int a = 0; a < 3; ++a) {
    const double count = std::round(field_of_view_mm[a] / voxel_size_mm[a]);
    grid.dims[a] = static_cast<int>(std::max(1.0, count));
  }
  const Eigen::Matrix3d linear = direction * voxel_size_mm.asDiagonal();
  const Eigen::Vector3d half_extent = 0.5 * (grid.dims.cast<double>() - Eigen::Vector3d::Ones());
  grid.world_from_voxel.setIdentity();
  grid.world_from_voxel.topLeftCorner<3, 3>() = linear;
  grid.world_from_voxel.topRightCorner<3, 1>() = center_mm - linear * half_extent;
  return grid;
}

ImageGrid GridSettings::grid() const {
  const auto direction = direction_from_axis_code(orientation);
  return make_centered_grid(field_of_view_mm, voxel_size_mm, center_mm,
                            direction ? *direction : Eigen::Matrix3d::Identity());
}

int largest_prime_factor(int n) {
  int largest = 1;
  for (long long p = 2; p * p <= n; ++p) {
    while (n % p == 0) {
      largest = static_cast<int>(p);
      n /= static_cast<int>(p);
    }
  }
  return n > 1 ? std::max(largest, n) : largest;
}

} // namespace phantasm
