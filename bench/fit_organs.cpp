// The Colin 27 organs' fits (data-synthetic/colin-head.yaml) piece by piece, one organ at a time:
// each organ's target from its labels, its base mesh (CGAL's surface mesher: a probe for the
// area, the sized mesh, a third when that misses the size; then the vertices moved to straddle
// the target), the bumps' fit, the patches' height bounds and the fit's measure against the source, each with
// its wall and processor time, and a hash of the fitted surface (the same hash: the same fit to
// the bit). Run with OMP_NUM_THREADS=1 for times that add up to a core's work.
// Usage: fit_organs [SCENE [ORGAN...]]
//   SCENE  default data-synthetic/colin-head.yaml
//   ORGAN  only these organs (default: every fitted one)

#include "anatomy/patch_fit.hpp"
#include "anatomy/phantom.hpp"
#include "bench/process_clock.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <set>
#include <string>

namespace {

using phantasm::bench::cpu_seconds;
using phantasm::bench::seconds_since;

/// FNV-1a over the bytes of doubles.
struct Hash {
  std::uint64_t value = 14695981039346656037ull;
  void add(double x) {
    unsigned char bytes[sizeof x];
    std::memcpy(bytes, &x, sizeof x);
    for (unsigned char b : bytes)
      value = (value ^ b) * 1099511628211ull;
  }
};

/// Wall and processor seconds of a piece of work.
struct Clock {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  double cpu = cpu_seconds();
  void print(const char* what) {
    std::printf(" %s %.2f/%.2f", what, seconds_since(wall), cpu_seconds() - cpu);
    wall = std::chrono::steady_clock::now();
    cpu = cpu_seconds();
  }
};

} // namespace

int main(int argc, char** argv) {
  using namespace phantasm;
  const std::string path =
      argc > 1 ? argv[1] : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/colin-head.yaml";
  const SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  const Scene& scene = *loaded.scene;
  const std::set<std::string> only(argv + std::min(argc, 2), argv + argc);
  StageReport report;
  Reporter quiet = Reporter::silent();
  const std::map<std::string, ShapeData> files = read_scene_shape_files(scene, report, quiet);
  std::printf("wall/CPU seconds: target, base mesh, bumps, height bounds, measure\n");
  Clock total;
  for (const OrganSettings& organ : scene.anatomy.organs) {
    const auto file = files.find(organ.name);
    if (organ.solid || file == files.end() || (!only.empty() && !only.count(organ.name))) continue;
    std::printf("%-18s", organ.name.c_str());
    Clock clock;
    const std::unique_ptr<ImplicitShape> target = target_shape(organ.shape, &file->second, organ.name);
    clock.print("target");
    PatchFitOptions options;
    options.base_triangles =
        organ.base_mesh_triangles > 0 ? organ.base_mesh_triangles : scene.anatomy.base_mesh_triangles;
    // As fit_patch_surface: the extracted base mesh, its vertices moved out to straddle the
    // target (a search along the normal at every edge's midpoint), then the bumps.
    const TriangleMesh on_target =
        fit_base_mesh(*target, options, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity());
    TriangleMesh base = on_target;
    base.vertices = straddle_vertices(on_target, *target, options.vertex_offset_factor);
    clock.print("base");
    PatchSurface surface(base, organ.name);
    fit_bumps(surface, *target, options);
    match_volume(surface, target->volume());
    clock.print("bumps");
    // The patches' height bounds, which the anatomy holds for the level sets.
    const std::vector<HeightRange> ranges = patch_height_ranges(surface);
    clock.print("ranges");
    // As the anatomy measures it: surface points about every millimetre.
    const SourceFit fit =
        measure_source_fit(surface, *target, surface_sample_level_for_spacing(surface, 1.0));
    clock.print("measure");
    Hash hash;
    for (Eigen::Index i = 0; i < base.vertices.size(); ++i)
      hash.add(base.vertices.data()[i]);
    for (Eigen::Index t = 0; t < surface.patch_count(); ++t)
      for (const PatchBump& b : surface.bumps(t)) {
        hash.add(b.amplitude_mm);
        hash.add(b.center_uv.x());
        hash.add(b.shape_uv(0, 0));
      }
    for (const HeightRange& range : ranges) {
      hash.add(range.lowest);
      hash.add(range.highest);
    }
    hash.add(fit.source_mean_mm);
    hash.add(fit.source_max_mm);
    std::printf(" | %ld patches, source max %.4f mm, hash %016llx\n",
                static_cast<long>(surface.patch_count()), fit.source_max_mm,
                static_cast<unsigned long long>(hash.value));
    std::fflush(stdout);
  }
  total.print("total");
  std::printf("\n");
  return 0;
}
