// Time and peak memory of the voxelization stage on the head (labels and fractions of both
// states, both displacement fields, Jacobian), at a given voxel size. One process per size, so
// the peak resident memory it prints is that run's.
// Usage: voxelize_head VOXEL_MM [SCENE]

#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  using namespace phantasm;
  if (argc < 2) {
    std::fprintf(stderr, "usage: voxelize_head VOXEL_MM [SCENE]\n");
    return 2;
  }
  const std::string path =
      argc > 2 ? argv[2] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml";
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  scene.grid.voxel_size_mm = Eigen::Vector3d::Constant(std::atof(argv[1]));
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport sim;
  const PhantomDeformation deformation = deform_phantom(scene.deformation, scene.organs, phantom, sim, quiet);
  const Phantom deformed = deformed_phantom(phantom, deformation);
  StageReport report;
  const auto start = std::chrono::steady_clock::now();
  const VoxelizedPhantom volumes = voxelize_phantom(scene.voxelization, scene.organs, scene.grid.grid(),
                                                    phantom, &deformed, &deformation, report, quiet);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("voxel %s mm: grid %d x %d x %d, voxelize %.2f s, peak resident %.0f MB\n", argv[1],
              volumes.grid.dims.x(), volumes.grid.dims.y(), volumes.grid.dims.z(), seconds,
              static_cast<double>(usage.ru_maxrss) / 1024.0);
  return 0;
}
