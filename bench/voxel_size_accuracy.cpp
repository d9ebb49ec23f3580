// Volume error against voxel size and time: voxelizes the reference head at several voxel
// sizes and prints, as CSV, the time and the largest relative error of a tissue's volume from
// fractions against the patch surfaces' exact volumes (for scripts/accuracy_plots.py).
// Usage: voxel_size_accuracy [SCENE]

#include "bench/exact_tissue_volumes.hpp"

#include <chrono>
#include <cstdio>

int main(int argc, char** argv) {
  using namespace phantasm;
  Scene scene = bench::scene_from_arguments(argc, argv);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  const auto exact = bench::exact_tissue_volumes(phantom);
  std::printf("voxel_mm,seconds,largest_volume_error\n");
  for (double voxel : {3.0, 2.0, 1.5, 1.0, 0.75}) {
    scene.grid.voxel_size_mm = Eigen::Vector3d::Constant(voxel);
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    const VoxelizedPhantom v = voxelize_phantom(scene.voxelization, scene.organs, scene.grid.grid(), phantom,
                                                nullptr, nullptr, report, quiet);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%g,%.3f,%.6g\n", voxel, seconds, bench::largest_volume_error(v, exact));
    std::fflush(stdout);
  }
  return 0;
}
