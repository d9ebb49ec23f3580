// Time of tessellating every organ's patch surface of a scene, the work behind the mesh files
// (each organ's surface in both states) and the landmarks' depth search. Builds the anatomy, or
// reads it from the anatomy cache CACHE when one is given, then tessellates all organs within
// TOLERANCE mm (default 0.2) ROUNDS times (default 5) and prints each round's time, the median,
// the triangle count and a SHA-256 of the meshes' vertices and faces (the same meshes give the
// same digest, so two builds can be compared).
// Usage: tessellate_organs [SCENE [TOLERANCE [ROUNDS [CACHE]]]]

#include "bench/exact_tissue_volumes.hpp"
#include "core/sha256.hpp"
#include "pipeline/run_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  using namespace phantasm;
  const Scene scene = bench::scene_from_arguments(argc, argv);
  const double tolerance = argc > 2 ? std::atof(argv[2]) : 0.2;
  const int rounds = argc > 3 ? std::max(1, std::atoi(argv[3])) : 5;
  Reporter quiet = Reporter::silent();
  const Simulation simulation = simulate(scene, quiet, SimulationStage::anatomy,
                                         argc > 4 ? std::filesystem::path(argv[4]) : std::filesystem::path());
  std::vector<double> seconds;
  std::string digest;
  long triangles = 0;
  for (int round = 0; round < rounds; ++round) {
    std::string bytes;
    triangles = 0;
    const auto start = std::chrono::steady_clock::now();
    std::vector<TriangleMesh> meshes;
    for (const Organ& organ : simulation.phantom.organs)
      if (organ.surface) meshes.push_back(organ.surface->tessellate(tolerance));
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    for (const TriangleMesh& mesh : meshes) {
      triangles += static_cast<long>(mesh.face_count());
      bytes.append(reinterpret_cast<const char*>(mesh.vertices.data()),
                   static_cast<std::size_t>(mesh.vertices.size()) * sizeof(double));
      bytes.append(reinterpret_cast<const char*>(mesh.faces.data()),
                   static_cast<std::size_t>(mesh.faces.size()) * sizeof(int));
    }
    digest = sha256_hex(bytes);
    std::printf("round %d: %.3f s\n", round + 1, seconds.back());
  }
  std::sort(seconds.begin(), seconds.end());
  std::printf("tessellation within %g mm of %zu organs: median %.3f s, %ld triangles, sha256 %s\n", tolerance,
              simulation.phantom.organs.size(), seconds[seconds.size() / 2], triangles, digest.c_str());
  return 0;
}
