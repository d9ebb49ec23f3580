// The voxelization's accuracy knob, measured: for each tessellation tolerance, the time to
// voxelize the reference head at 1 mm and the largest relative error of a tissue's volume from
// fractions against the exact volumes of the patch surfaces (an organ's own tissue fills its
// volume minus its children's). Prints a Markdown table.
// Usage: tessellation_tolerance [SCENE]

#include "voxelize/voxelize_phantom.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

int main(int argc, char** argv) {
  using namespace phantasm;
  const std::string path =
      argc > 1 ? argv[1] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml";
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene, {}, quiet);
  std::map<std::string, double> exact; // mm^3 per tissue
  for (std::size_t o = 0; o < phantom.organs.size(); ++o) {
    if (!phantom.organs[o].surface) continue;
    double own = phantom.organs[o].surface->volume();
    for (const Organ& child : phantom.organs)
      if (child.inside == phantom.organs[o].name && child.surface) own -= child.surface->volume();
    exact[phantom.organs[o].tissue] += own;
  }
  std::printf("| tessellation tolerance | voxelize (reference, 1 mm) | largest tissue volume error "
              "|\n|---|---|---|\n");
  for (double tolerance : {0.4, 0.2, 0.1, 0.05}) {
    scene.voxelization.tessellation_tolerance_mm = tolerance;
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    const VoxelizedPhantom v = voxelize_phantom(scene, phantom, nullptr, nullptr, report, quiet);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double voxel = v.grid.spacing_mm.prod();
    double worst = 0.0;
    for (std::size_t t = 0; t < v.tissues.size(); ++t) {
      double sum = 0.0;
      for (float f : v.reference.fractions[t])
        sum += f;
      worst = std::max(worst, std::abs(sum * voxel / exact[v.tissues[t]] - 1.0));
    }
    std::printf("| %.2f mm | %.1f s | %.3f %% |\n", tolerance, seconds, 100.0 * worst);
    std::fflush(stdout);
  }
  return 0;
}
