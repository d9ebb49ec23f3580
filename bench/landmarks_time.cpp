// Time of the landmarks alone (organ_landmarks: each organ's deepest point and extreme surface
// points), as the voxelization computes them after its displacement fields. The scene's anatomy
// is built, or read from the anatomy cache CACHE when one is given ("" or "-": none), and
// deformed as a run would, at the voxel size VOXEL_MM ("" or "-": the scene's); then the
// deformation map is built as voxelize_phantom builds it, and organ_landmarks is timed REPEATS
// times (default 1), wall and CPU (on a shared machine the CPU time tells the work apart from the
// waiting). It prints the seconds after each organ of the first repeat, the peak resident memory
// the landmarks add, and a hash (FNV-1a) of each state's landmarks CSV, so that two builds can be
// checked for the same landmarks; with CSV_PREFIX, the CSVs are also written to
// CSV_PREFIX-reference.csv and CSV_PREFIX-deformed.csv. DEPTH says how depths are measured:
// "labels" (the default, as a run does: the reference state is voxelized first, during the set-up,
// and its labels given) or "surfaces" (every depth from the tessellated surfaces). Then the dense
// landmarks (dense_landmarks, the scene's outputs.dense_landmarks per organ) are timed once.
// Usage: landmarks_time SCENE [CACHE [VOXEL_MM [REPEATS [CSV_PREFIX [DEPTH]]]]]

#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "voxelize/dense_landmarks.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace {

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// The resident memory now and its peak since the last reset_peak_resident() (VmRSS and VmHWM
/// of /proc/self/status), MB.
double resident_mb(const std::string& key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind(key + ":", 0) == 0) return std::atof(line.c_str() + key.size() + 1) / 1024.0;
  return 0.0;
}

/// Restarts the peak resident memory from the current one (Linux 4.0 and later), so that the
/// peak of the landmarks alone is seen.
void reset_peak_resident() {
  std::ofstream("/proc/self/clear_refs") << "5";
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm;
  if (argc < 2) {
    std::fprintf(stderr, "usage: landmarks_time SCENE [CACHE [VOXEL_MM [REPEATS [CSV_PREFIX [DEPTH]]]]]\n");
    return 2;
  }
  const std::string path = argv[1];
  const std::string cache = argc > 2 && std::string(argv[2]) != "-" ? argv[2] : "";
  const int repeats = argc > 4 ? std::max(1, std::atoi(argv[4])) : 1;
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  if (argc > 3 && std::atof(argv[3]) > 0.0)
    scene.grid.voxel_size_mm = Eigen::Vector3d::Constant(std::atof(argv[3]));
  Reporter quiet = Reporter::silent();
  const auto setup_start = std::chrono::steady_clock::now();
  const Simulation simulation =
      simulate(scene, quiet, SimulationStage::deformation, std::filesystem::path(cache));
  const Phantom& phantom = simulation.phantom;
  const PhantomDeformation* deformation = simulation.deformation ? &*simulation.deformation : nullptr;
  // The tolerance and the map's extension as voxelize_phantom chooses them.
  const Eigen::Vector3d spacing = scene.grid.grid().spacing_mm;
  const double tolerance_mm = std::clamp(spacing.minCoeff(), 0.5, 2.0);
  std::optional<DeformationMap> map;
  if (deformation) map.emplace(deformation->bodies, 2.0 * spacing.maxCoeff());
  const bool from_labels = argc <= 6 || std::string(argv[6]) != "surfaces";
  // The reference labels, as voxelize_phantom has them when it comes to the landmarks.
  std::optional<VoxelizedPhantom> voxelized;
  ReferenceLabels labels;
  if (from_labels) {
    StageReport report;
    voxelized.emplace(voxelize_phantom(scene.voxelization, scene.organs, scene.grid.grid(), phantom, nullptr,
                                       nullptr, report, quiet));
    labels = {&voxelized->grid, &voxelized->reference.labels};
  }
  std::printf("%s: %zu organs, voxel %.3g mm, depths from the %s (tolerance %.3g mm), set up in %.1f s\n",
              path.c_str(), phantom.organs.size(), spacing.minCoeff(), from_labels ? "labels" : "surfaces",
              tolerance_mm,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - setup_start).count());
  std::fflush(stdout);

  std::vector<Landmark> landmarks;
  for (int r = 0; r < repeats; ++r) {
    std::vector<double> organ_seconds;
    reset_peak_resident();
    const double resident_before = resident_mb("VmRSS");
    const double cpu_before = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    const auto organ_done = [&] {
      organ_seconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    };
    std::vector<std::string> warnings;
    landmarks = organ_landmarks(phantom, deformation, map ? &*map : nullptr, tolerance_mm, &warnings,
                                organ_done, labels);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double cpu = cpu_seconds() - cpu_before;
    if (r == 0) {
      std::printf("seconds after each organ:");
      for (const double s : organ_seconds)
        std::printf(" %.2f", s);
      std::printf("\n");
      for (const std::string& w : warnings)
        std::printf("warning: %s\n", w.c_str());
    }
    std::printf("landmarks: %.2f s wall, %.2f s CPU, peak resident %.0f MB above the %.0f MB before\n",
                seconds, cpu, resident_mb("VmHWM") - resident_before, resident_before);
    std::fflush(stdout);
  }
  {
    const double cpu_before = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::string> warnings;
    const std::vector<Landmark> dense =
        dense_landmarks(phantom, deformation, map ? &*map : nullptr, scene.voxelization.dense_landmarks,
                        phantom.seed, &warnings);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const std::string& w : warnings)
      std::printf("warning: %s\n", w.c_str());
    std::printf("dense landmarks: %zu (%d per organ asked), %.2f s wall, %.2f s CPU, deformed CSV %016llx\n",
                dense.size(), scene.voxelization.dense_landmarks, seconds, cpu_seconds() - cpu_before,
                static_cast<unsigned long long>(fnv1a(landmarks_csv(dense, true))));
  }
  const std::string reference_csv = landmarks_csv(landmarks, false),
                    deformed_csv = landmarks_csv(landmarks, true);
  std::printf("%zu landmarks, reference CSV %016llx, deformed CSV %016llx\n", landmarks.size(),
              static_cast<unsigned long long>(fnv1a(reference_csv)),
              static_cast<unsigned long long>(fnv1a(deformed_csv)));
  if (argc > 5 && std::string(argv[5]) != "-") {
    std::ofstream(std::string(argv[5]) + "-reference.csv", std::ios::binary) << reference_csv;
    std::ofstream(std::string(argv[5]) + "-deformed.csv", std::ios::binary) << deformed_csv;
  }
  return 0;
}
