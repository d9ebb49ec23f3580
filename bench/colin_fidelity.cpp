// Fidelity and cost of the Colin 27 head (data-synthetic/colin-head.yaml, docs/anatomy-colin27.md):
// builds the reference phantom from the derived labels, voxelizes it on the scene's grid and
// compares the voxelized labels with the source labels resampled to that grid (nearest voxel
// centre): Dice per organ and per tissue, volumes (from the partial-volume fractions and from the
// labels), and each organ's fit to its source (mean and largest distance, anatomy/patch_fit.hpp). Times the
// atlas derivation, the anatomy, each organ's level set (one at a time, on one thread's worth of
// work each) and the reference voxelization; peak memory at the end.
// Usage: colin_fidelity [SCENE [VOXEL_MM]]
//   SCENE     default data-synthetic/colin-head.yaml (a copy with other base sizes or smoothing)
//   VOXEL_MM  overrides the scene's voxel size (the source labels are 1 mm: Dice is meaningful at 1)

#include "anatomy/phantom.hpp"
#include "atlas/atlas_labels.hpp"
#include "bench/process_clock.hpp"
#include "io/shape_files.hpp"
#include "scene/scene.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>

namespace {

using phantasm::bench::cpu_seconds;
using phantasm::bench::seconds_since;

double dice(std::int64_t both, std::int64_t a, std::int64_t b) {
  return a + b == 0 ? 1.0 : 2.0 * static_cast<double>(both) / static_cast<double>(a + b);
}

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm;
  const std::string path =
      argc > 1 ? argv[1] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/colin-head.yaml";
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  if (argc > 2) scene.grid.voxel_size_mm = Eigen::Vector3d::Constant(std::atof(argv[2]));
  const ImageGrid grid = scene.grid.grid();
  Reporter quiet = Reporter::silent();

  // The source labels, as the run derives them (once).
  auto start = std::chrono::steady_clock::now();
  double cpu = cpu_seconds();
  AtlasLabels source = derive_atlas_labels("colin27");
  std::printf("atlas derivation: %.1f s (%.1f s CPU)\n", seconds_since(start), cpu_seconds() - cpu);
  const AtlasLoader loader = [&source](const std::string&) {
    AtlasLabelVolume volume;
    volume.grid = source.head.grid;
    volume.source = source.source;
    for (const HeadLabelInfo& info : source.head.table)
      if (info.label != 0) volume.names[info.name] = info.label;
    volume.labels = std::make_shared<const std::vector<std::int32_t>>(source.head.labels);
    return volume;
  };

  start = std::chrono::steady_clock::now();
  cpu = cpu_seconds();
  const std::map<std::string, ShapeData> files = read_shape_files(scene.anatomy, loader, grid);
  const Phantom phantom = build_phantom(scene.anatomy, files, quiet);
  std::printf("anatomy: %.1f s (%.1f s CPU)\n", seconds_since(start), cpu_seconds() - cpu);

  const double voxel = grid.spacing_mm.minCoeff();
  std::printf("\nlevel sets at %.3g mm, one organ at a time:\n", voxel);
  std::printf("%-18s %8s %10s %8s %8s\n", "organ", "patches", "band vox", "wall s", "CPU s");
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    start = std::chrono::steady_clock::now();
    cpu = cpu_seconds();
    const LevelSet level_set(*organ.surface, voxel);
    std::printf("%-18s %8ld %10zu %8.2f %8.2f\n", organ.name.c_str(),
                static_cast<long>(organ.surface->base_mesh().face_count()), level_set.active_voxel_count(),
                seconds_since(start), cpu_seconds() - cpu);
  }

  start = std::chrono::steady_clock::now();
  cpu = cpu_seconds();
  StageReport report;
  const VoxelizedPhantom volumes =
      voxelize_phantom(scene.voxelization, scene.organs, grid, phantom, nullptr, nullptr, report, quiet);
  std::printf("\nreference voxelization (supersampling %d): %.1f s (%.1f s CPU)\n",
              scene.voxelization.supersampling, seconds_since(start), cpu_seconds() - cpu);

  // The source labels at the grid's voxel centres (nearest source voxel; outside: background).
  const ImageGrid& source_grid = source.head.grid;
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  std::vector<std::int32_t> resampled(count, 0);
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const Eigen::Vector3d s =
            source_grid.index_from_world(grid.world_from_index(Eigen::Vector3d(i, j, k))).array().round();
        if ((s.array() < 0.0).any() || (s.array() >= source_grid.dims.cast<double>().array()).any()) continue;
        resampled[voxel_index(grid.dims, i, j, k)] = source.head.labels[voxel_index(
            source_grid.dims, static_cast<int>(s.x()), static_cast<int>(s.y()), static_cast<int>(s.z()))];
      }
  std::map<std::int32_t, std::string> tissue_of_label;
  std::map<std::string, std::int32_t> label_of_name;
  for (const HeadLabelInfo& info : source.head.table) {
    tissue_of_label[info.label] = info.tissue;
    label_of_name[info.name] = info.label;
  }
  const double voxel_ml = grid.spacing_mm.prod() / 1000.0;

  // Per organ: its voxels (the label map) against its own source labels.
  std::printf("\n%-18s %8s %10s %10s %8s %9s %9s\n", "organ", "Dice", "labels ml", "source ml", "error",
              "fit mean", "fit max");
  for (std::size_t o = 0; o < phantom.organs.size(); ++o) {
    const Organ& organ = phantom.organs[o];
    const OrganSettings& settings = scene.anatomy.organs[o];
    std::set<std::int32_t> own;
    for (const std::string& name : settings.shape.labels)
      own.insert(label_of_name.count(name) ? label_of_name[name] : std::atoi(name.c_str()));
    std::int64_t a = 0, b = 0, both = 0;
    for (std::size_t n = 0; n < count; ++n) {
      const bool in_a = volumes.reference.labels[n] == static_cast<std::int32_t>(o) + 1;
      const bool in_b = own.count(resampled[n]) > 0;
      a += in_a;
      b += in_b;
      both += in_a && in_b;
    }
    std::printf("%-18s %8.4f %10.1f %10.1f %7.2f%% %8.2f %9.2f\n", organ.name.c_str(), dice(both, a, b),
                static_cast<double>(a) * voxel_ml, static_cast<double>(b) * voxel_ml,
                100.0 * (static_cast<double>(a) / static_cast<double>(std::max<std::int64_t>(b, 1)) - 1.0),
                organ.fit.source_mean_mm, organ.fit.source_max_mm);
  }

  // Per tissue: the tissue of each voxel's organ against the tissue of its source label; volumes
  // from the label map and from the partial-volume fractions.
  std::printf("\n%-16s %8s %10s %12s %10s %8s\n", "tissue", "Dice", "labels ml", "fractions ml", "source ml",
              "error");
  for (std::size_t t = 0; t < volumes.tissues.size(); ++t) {
    const std::string& tissue = volumes.tissues[t];
    std::int64_t a = 0, b = 0, both = 0;
    const double fraction_sum = volumes.reference.fraction_sum(static_cast<int>(t));
    for (std::size_t n = 0; n < count; ++n) {
      const std::int32_t l = volumes.reference.labels[n];
      const bool in_a = l > 0 && l <= static_cast<std::int32_t>(phantom.organs.size()) &&
                        phantom.organs[static_cast<std::size_t>(l - 1)].tissue == tissue;
      const bool in_b = tissue_of_label[resampled[n]] == tissue;
      a += in_a;
      b += in_b;
      both += in_a && in_b;
    }
    std::printf("%-16s %8.4f %10.1f %12.1f %10.1f %7.2f%%\n", tissue.c_str(), dice(both, a, b),
                static_cast<double>(a) * voxel_ml, fraction_sum * voxel_ml, static_cast<double>(b) * voxel_ml,
                100.0 * (fraction_sum / std::max<double>(static_cast<double>(b), 1.0) - 1.0));
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("\npeak resident %.0f MB\n", static_cast<double>(usage.ru_maxrss) / 1024.0);
  return 0;
}
