// Time and peak memory of the voxelization stage on the head (labels and fractions of both
// states, both displacement fields, Jacobian), at a given voxel size. One process per size, so
// the peak resident memory it prints is that run's. PATH chooses the implementation: "new" (the
// default: level sets from the patch surfaces), "old" (level sets through tessellations and
// mesh-to-volume), or "both" (old, then new, in one process: the times side by side; the peak
// memory is then the larger of the two). The fields take the same path in both. SCENE (default
// data-synthetic/head.yaml) may be any scene, the Colin head included: its anatomy is built, or
// read from the anatomy cache CACHE when one is given, and deformed as a run would before the
// voxelization is timed.
// Usage: voxelize_head VOXEL_MM [PATH [SCENE [CACHE]]]

#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  using namespace phantasm;
  const std::string path_choice = argc > 2 ? argv[2] : "new";
  if (argc < 2 || (path_choice != "new" && path_choice != "old" && path_choice != "both")) {
    std::fprintf(stderr, "usage: voxelize_head VOXEL_MM [new|old|both [SCENE [CACHE]]]\n");
    return 2;
  }
  const std::string path =
      argc > 3 ? argv[3] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml";
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  scene.grid.voxel_size_mm = Eigen::Vector3d::Constant(std::atof(argv[1]));
  Reporter quiet = Reporter::silent();
  const Simulation simulation = simulate(scene, quiet, SimulationStage::deformation,
                                         argc > 4 ? std::filesystem::path(argv[4]) : std::filesystem::path());
  if (!simulation.deformation || !simulation.deformed) {
    std::fprintf(stderr, "%s: the scene deforms nothing\n", path.c_str());
    return 2;
  }
  const Phantom& phantom = simulation.phantom;
  const PhantomDeformation& deformation = *simulation.deformation;
  const Phantom& deformed = *simulation.deformed;
  for (const bool old : {true, false}) {
    if ((old && path_choice == "new") || (!old && path_choice == "old")) continue;
    VoxelizationSettings settings = scene.voxelization;
    settings.level_sets_from_tessellation = old;
    StageReport report;
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    const auto start = std::chrono::steady_clock::now();
    const VoxelizedPhantom volumes = voxelize_phantom(settings, scene.organs, scene.grid.grid(), phantom,
                                                      &deformed, &deformation, report, quiet);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    auto cpu = [](const rusage& u) {
      return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
             1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
    };
    // CPU time too: on a shared machine it tells the work apart from the waiting. The partial
    // voxels are those whose fractions are stored (TissueVolumes::partial_voxels).
    const auto voxels = static_cast<double>(volumes.grid.voxel_count());
    const auto partial = [&](const TissueVolumes& v) { return static_cast<double>(v.partial_voxels.size()); };
    std::printf(
        "voxel %s mm, %s path: grid %d x %d x %d, voxelize %.2f s (%.2f s CPU), peak resident %.0f MB; "
        "partial voxels %.2f %% (reference) and %.2f %% (deformed) of the grid\n",
        argv[1], old ? "old" : "new", volumes.grid.dims.x(), volumes.grid.dims.y(), volumes.grid.dims.z(),
        seconds, cpu(usage) - cpu(before), static_cast<double>(usage.ru_maxrss) / 1024.0,
        100.0 * partial(volumes.reference) / voxels, 100.0 * partial(*volumes.deformed) / voxels);
    std::fflush(stdout);
  }
  return 0;
}
