// Building the distance structure of a fine closed surface (geometry/mesh_signed_distance.hpp):
// the landmark search builds one per organ over its tessellation within the voxel edge (millions
// of triangles on real anatomy), so its cost shows in every run's voxelization.
// Usage: build/release/bench/bench_geometry [--benchmark_filter=...]

#include "geometry/mesh_signed_distance.hpp"
#include "geometry/triangle_mesh.hpp"

#include <benchmark/benchmark.h>

namespace {

// An icosphere of 20 x 4^level triangles: construction (vertex and edge numbering), the corner
// angles and pseudonormals, and the search tree.
void signed_distance_mesh_build(benchmark::State& state) {
  const phantasm::TriangleMesh sphere = phantasm::unit_icosphere(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    phantasm::SignedDistanceMesh mesh(sphere.faces);
    mesh.update(sphere.vertices);
    mesh.build_search_tree();
    benchmark::DoNotOptimize(mesh);
  }
  state.counters["triangles"] = static_cast<double>(sphere.face_count());
}

} // namespace

BENCHMARK(signed_distance_mesh_build)->DenseRange(5, 8)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
