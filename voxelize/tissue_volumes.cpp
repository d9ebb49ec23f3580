#include "voxelize/tissue_volumes.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"

#include <omp.h>

#include <atomic>
#include <cmath>
#include <string>

namespace phantasm {

TissueVolumes voxelize_tissues(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                               int tissue_count, int supersampling) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  TissueVolumes out;
  out.labels.assign(count, 0);
  out.background.assign(count, 0.0f);
  out.fractions.assign(static_cast<std::size_t>(tissue_count), std::vector<float>(count, 0.0f));
  const int n = std::max(1, supersampling);
  const double half_diagonal = 0.5 * grid.spacing_mm.norm();
  const Eigen::Matrix3d axes = grid.world_from_voxel.topLeftCorner<3, 3>();
  std::size_t sampled = 0;
  std::atomic<int> slabs_done{0};
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
#pragma omp parallel reduction(+ : sampled)
  {
    std::vector<LevelSet::Probe> probes;
    for (const VoxelizedOrgan& organ : organs)
      probes.emplace_back(*organ.level_set);
    std::vector<double> centre_distance(organs.size());
    std::vector<double> organ_share(organs.size());
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nz; ++k) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const int slab = slabs_done.fetch_add(1) + 1;
      if (progress_detail_due())
        progress_detail("tissue fractions, slab " + std::to_string(slab) + "/" + std::to_string(nz));
      for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
          const std::size_t index = voxel_index(grid.dims, i, j, k);
          const Eigen::Vector3d centre = grid.world_from_index(Eigen::Vector3d(i, j, k));
          bool decided = true;
          for (std::size_t o = 0; o < organs.size(); ++o) {
            centre_distance[o] = probes[o](centre);
            if (std::abs(centre_distance[o]) < half_diagonal) decided = false;
          }
          auto deepest = [&](auto&& inside) {
            int best = -1;
            for (std::size_t o = 0; o < organs.size(); ++o) {
              if (inside(o) && (best < 0 || organs[o].depth >= organs[static_cast<std::size_t>(best)].depth))
                best = static_cast<int>(o);
            }
            return best;
          };
          std::fill(organ_share.begin(), organ_share.end(), 0.0);
          double background = 0.0;
          if (decided) {
            const int owner = deepest([&](std::size_t o) { return centre_distance[o] < 0.0; });
            (owner < 0 ? background : organ_share[static_cast<std::size_t>(owner)]) = 1.0;
          } else {
            ++sampled;
            const double weight = 1.0 / (n * n * n);
            for (int c = 0; c < n; ++c) {
              for (int b = 0; b < n; ++b) {
                for (int a = 0; a < n; ++a) {
                  const Eigen::Vector3d offset((a + 0.5) / n - 0.5, (b + 0.5) / n - 0.5, (c + 0.5) / n - 0.5);
                  const Eigen::Vector3d x = centre + axes * offset;
                  const int owner = deepest([&](std::size_t o) {
                    return std::abs(centre_distance[o]) >= half_diagonal ? centre_distance[o] < 0.0
                                                                         : probes[o](x) < 0.0;
                  });
                  (owner < 0 ? background : organ_share[static_cast<std::size_t>(owner)]) += weight;
                }
              }
            }
          }
          int label = 0;
          double largest = background;
          double empty = background; // outside every organ, or in a gap filled with air
          for (std::size_t o = 0; o < organs.size(); ++o) {
            if (organs[o].tissue < 0) {
              empty += organ_share[o];
            } else {
              out.fractions[static_cast<std::size_t>(organs[o].tissue)][index] +=
                  static_cast<float>(organ_share[o]);
            }
            if (organ_share[o] > largest) {
              largest = organ_share[o];
              label = organs[o].label;
            }
          }
          out.background[index] = static_cast<float>(empty);
          out.labels[index] = label;
        }
      }
    }
  }
  throw_if_cancelled();
  out.supersampled_voxels = sampled;
  return out;
}

} // namespace phantasm
