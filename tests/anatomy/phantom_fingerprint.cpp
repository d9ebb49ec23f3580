// Builds a scene's phantom and prints the SHA-256 of every base vertex, bump amplitude, tet
// vertex and tet, so tests can compare phantoms built in separate processes.
// Usage: phantom_fingerprint SCENE.yaml SEED [--surfaces-only]
// --surfaces-only builds every closed organ as a surface (no CGAL tet mesh).

#include "anatomy/phantom.hpp"
#include "core/sha256.hpp"
#include "scene/scene.hpp"

#include <cstdlib>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  using namespace phantasm;
  if (argc < 3 || argc > 4) {
    std::cerr << "usage: phantom_fingerprint SCENE.yaml SEED [--surfaces-only]\n";
    return 2;
  }
  SceneLoadResult result = load_scene(argv[1]);
  if (!result.scene) {
    std::cerr << format_diagnostics(result.problems);
    return 2;
  }
  Scene scene = *result.scene;
  scene.seed = std::strtoull(argv[2], nullptr, 10);
  if (argc == 4 && std::string(argv[3]) == "--surfaces-only") {
    for (auto& organ : scene.anatomy.organs)
      organ.solid = false;
  }
  resolve_stage_settings(scene);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  std::string bytes;
  auto add = [&](const double* data, Eigen::Index count) {
    bytes.append(reinterpret_cast<const char*>(data), static_cast<std::size_t>(count) * sizeof(double));
  };
  for (const Organ& organ : phantom.organs) {
    if (organ.surface) {
      add(organ.surface->base_mesh().vertices.data(), organ.surface->base_mesh().vertices.size());
      for (Eigen::Index t = 0; t < organ.surface->patch_count(); ++t) {
        for (const PatchBump& bump : organ.surface->bumps(t))
          add(&bump.amplitude_mm, 1);
      }
    }
    if (organ.solid) {
      add(organ.solid->vertices.data(), organ.solid->vertices.size());
      const Eigen::MatrixX4i& tets = organ.solid->tets;
      bytes.append(reinterpret_cast<const char*>(tets.data()),
                   static_cast<std::size_t>(tets.size()) * sizeof(int));
    }
  }
  std::cout << sha256_hex(bytes) << '\n';
  return 0;
}
