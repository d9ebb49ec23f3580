// The deformation's speed/accuracy knob, anatomy.tet_size_mm: the scene's deformation solved on
// body meshes of several tet sizes, each compared with the finest. Prints a Markdown table (the
// ones of docs/performance.md and docs/deformation.md): tets, CSF tets, time of the stage
// (meshing included), and the displacement error of every moved organ's surface vertices
// against the finest size (RMS and largest, mm), with the finest run's largest displacement for
// scale.
// Usage: tet_size_accuracy [SCENE] [SIZE_MM ...]   (default: the head at 30 16 10 7 mm and the finest, 5)
// PHANTASM_ANATOMY_CACHE=DIR: the anatomy cache folder (docs/batch.md), so that a heavy anatomy is built
// once.

#include "anatomy/phantom.hpp"
#include "core/format.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

struct Run {
  double size_mm = 0.0;
  double seconds = 0.0;
  long tets = 0;
  std::string materials; ///< the log's "materials by tet" list
  phantasm::PhantomDeformation result;
};

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm;
  const std::string path =
      argc > 1 ? argv[1] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml";
  std::vector<double> sizes;
  for (int a = 2; a < argc; ++a)
    sizes.push_back(std::atof(argv[a]));
  if (sizes.empty()) sizes = {30.0, 16.0, 10.0, 7.0, 5.0};
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  const Scene& scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  // The anatomy as a run builds it (shape files and atlases read, PHANTASM_ANATOMY_CACHE used
  // when set, so that repeated measurements of a heavy anatomy build it once).
  const char* cache = std::getenv("PHANTASM_ANATOMY_CACHE");
  Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy,
                             cache != nullptr ? std::filesystem::path(cache) : std::filesystem::path())
                        .phantom;
  std::vector<Run> runs;
  for (double size : sizes) {
    phantom.tet_size_mm = size;
    Run run;
    run.size_mm = size;
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    run.result = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const DeformedBody& body : run.result.bodies)
      run.tets += static_cast<long>(body.tets.rows());
    for (const std::string& line : report.modelled) {
      if (line.find("one tet mesh") != std::string::npos) std::fprintf(stderr, "%s\n", line.c_str());
      const auto at = line.find("materials by tet:");
      if (at != std::string::npos) run.materials += line.substr(at + 18, line.size() - at - 19);
    }
    std::fprintf(stderr, "tet size %g mm: %ld tets, %.1f s\n", size, run.tets, run.seconds);
    runs.push_back(std::move(run));
  }
  const Run& finest = runs.back();
  double largest_displacement = 0.0;
  for (std::size_t i = 0; i < finest.result.organs.size(); ++i) {
    const Eigen::MatrixX3d& rest = phantom.organs[i].surface ? phantom.organs[i].surface->rest_positions()
                                                             : finest.result.organs[i].surface_mm;
    if (rest.rows() == finest.result.organs[i].surface_mm.rows())
      largest_displacement = std::max(
          largest_displacement, (finest.result.organs[i].surface_mm - rest).rowwise().norm().maxCoeff());
  }
  std::printf("Finest: tet size %g mm, largest surface displacement %.2f mm\n\n", finest.size_mm,
              largest_displacement);
  std::printf("| tet size | tets | materials by tet | time | RMS error | largest error |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (const Run& run : runs) {
    double sum = 0.0, largest = 0.0;
    long count = 0;
    for (std::size_t i = 0; i < run.result.organs.size(); ++i) {
      const OrganDeformation& d = run.result.organs[i];
      if (d.moved_by == "fixed" || d.moved_by == "rigid") continue;
      const Eigen::VectorXd error = (d.surface_mm - finest.result.organs[i].surface_mm).rowwise().norm();
      sum += error.squaredNorm();
      largest = std::max(largest, error.maxCoeff());
      count += static_cast<long>(error.size());
    }
    const bool reference = &run == &finest;
    std::printf("| %g mm | %ld | %s | %.1f s | %s | %s |\n", run.size_mm, run.tets, run.materials.c_str(),
                run.seconds,
                reference ? "(reference)" : format_number(std::sqrt(sum / std::max(1L, count))).c_str(),
                reference ? "" : format_number(largest).c_str());
  }
  return 0;
}
