// The voxelization's accuracy knob, measured: level sets from the patch surfaces directly, then
// through tessellations; for each tessellation tolerance, the time to
// voxelize the reference head at 1 mm and the largest relative error of a tissue's volume from
// fractions against the exact volumes of the patch surfaces (an organ's own tissue fills its
// volume minus its children's). Prints a Markdown table.
// Usage: tessellation_tolerance [SCENE]

#include "bench/exact_tissue_volumes.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

int main(int argc, char** argv) {
  using namespace phantasm;
  Scene scene = bench::scene_from_arguments(argc, argv);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  const auto exact = bench::exact_tissue_volumes(phantom);
  std::printf("| tessellation tolerance | voxelize (reference, 1 mm) | largest tissue volume error "
              "|\n|---|---|---|\n");
  // Tolerance 0: the level sets from the patch surfaces directly (the default path).
  for (double tolerance : {0.0, 0.4, 0.2, 0.1, 0.05}) {
    scene.voxelization.level_sets_from_tessellation = tolerance > 0.0;
    scene.voxelization.tessellation_tolerance_mm = tolerance > 0.0 ? tolerance : 0.2;
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    const VoxelizedPhantom v = voxelize_phantom(scene.voxelization, scene.organs, scene.grid.grid(), phantom,
                                                nullptr, nullptr, report, quiet);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double worst = bench::largest_volume_error(v, exact);
    if (tolerance > 0.0) {
      std::printf("| %.2f mm | %.1f s | %.3f %% |\n", tolerance, seconds, 100.0 * worst);
    } else {
      std::printf("| none (patch surfaces directly) | %.1f s | %.3f %% |\n", seconds, 100.0 * worst);
    }
    std::fflush(stdout);
  }
  return 0;
}
