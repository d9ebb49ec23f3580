// Helpers of the benchmark programs: the scene from the command line and the exact tissue
// volumes of a phantom from its patch surfaces, to measure voxelized fractions against.
#pragma once

// Exact tissue volumes of a phantom from its patch surfaces (an organ's own tissue fills its
// volume minus its children's), and the largest relative error of volumes from fractions.

#include "anatomy/phantom.hpp"
#include "scene/scene.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

namespace phantasm::bench {

/// The scene named by the first argument (default: the head), or the program ends with its
/// problems (exit 2).
inline Scene scene_from_arguments(int argc, char** argv) {
  const std::string path =
      argc > 1 ? argv[1] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml";
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    std::exit(2);
  }
  return *loaded.scene;
}

inline std::map<std::string, double> exact_tissue_volumes(const Phantom& phantom) {
  std::map<std::string, double> exact; // mm^3 per tissue
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    double own = organ.surface->volume();
    for (const Organ& child : phantom.organs)
      if (child.inside == organ.name && child.surface) own -= child.surface->volume();
    exact[organ.tissue] += own;
  }
  return exact;
}

inline double largest_volume_error(const VoxelizedPhantom& v, const std::map<std::string, double>& exact) {
  const double voxel = v.grid.spacing_mm.prod();
  double worst = 0.0;
  for (std::size_t t = 0; t < v.tissues.size(); ++t) {
    const double sum = v.reference.fraction_sum(static_cast<int>(t));
    worst = std::max(worst, std::abs(sum * voxel / exact.at(v.tissues[t]) - 1.0));
  }
  return worst;
}

} // namespace phantasm::bench
