#include "evaluation/digital_jacobian.hpp"

#include "geometry/ras_lps.hpp"

#include <Eigen/Dense>

#include <array>

namespace phantasm {
namespace {

/// The two ways to cut a cube (corners numbered i + 2 j + 4 k) into five tetrahedra, each
/// listed with positive orientation in the undeformed cube.
using Tet = std::array<int, 4>;
constexpr std::array<std::array<Tet, 5>, 2> k_cuttings = {{
    {{{0, 1, 2, 4}, {3, 2, 1, 7}, {5, 1, 4, 7}, {6, 4, 2, 7}, {1, 2, 4, 7}}},
    {{{1, 0, 5, 3}, {3, 2, 0, 6}, {4, 0, 6, 5}, {7, 6, 3, 5}, {0, 3, 6, 5}}},
}};

double signed_volume(const std::array<Eigen::Vector3d, 8>& p, const Tet& t) {
  return (p[t[1]] - p[t[0]]).dot((p[t[2]] - p[t[0]]).cross(p[t[3]] - p[t[0]])) / 6.0;
}

} // namespace

FoldingVolume non_diffeomorphic_volume(const DisplacementField& field, const std::vector<bool>& region) {
  const ImageGrid& grid = field.grid;
  const Eigen::Vector3i& dims = grid.dims;
  // u in voxel units: the map in index space, whose undeformed cube has volume 1.
  const Eigen::Matrix3d index_from_ras = grid.world_from_voxel.topLeftCorner<3, 3>().inverse();
  FoldingVolume result;
  for (int k = 0; k + 1 < dims.z(); ++k)
    for (int j = 0; j + 1 < dims.y(); ++j)
      for (int i = 0; i + 1 < dims.x(); ++i) {
        if (!region[voxel_index(dims, i, j, k)]) continue;
        std::array<Eigen::Vector3d, 8> p;
        for (int c = 0; c < 8; ++c) {
          const int a = i + (c & 1), b = j + ((c >> 1) & 1), d = k + ((c >> 2) & 1);
          p[c] = Eigen::Vector3d(a, b, d) +
                 index_from_ras * ras_from_lps(field.lps_mm[voxel_index(dims, a, b, d)]);
        }
        double negative = 0.0;
        for (const auto& cutting : k_cuttings)
          for (const Tet& t : cutting)
            negative += std::max(0.0, -signed_volume(p, t));
        ++result.cubes;
        if (negative > 0.0) ++result.folded_cubes;
        result.ndv_voxels += 0.5 * negative;
      }
  if (result.cubes > 0) result.ndv_percent = 100.0 * result.ndv_voxels / static_cast<double>(result.cubes);
  return result;
}

} // namespace phantasm
