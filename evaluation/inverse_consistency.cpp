#include "evaluation/inverse_consistency.hpp"

namespace phantasm {

std::vector<double> inverse_consistency_errors(const DisplacementField& forward,
                                               const DisplacementField& backward,
                                               const std::vector<bool>& mask) {
  const ImageGrid& grid = forward.grid;
  std::vector<double> errors;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        if (!mask[v]) continue;
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        errors.push_back((backward.moved(forward.moved(x)) - x).norm());
      }
  return errors;
}

} // namespace phantasm
