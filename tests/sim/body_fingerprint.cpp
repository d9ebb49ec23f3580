// Builds a scene's anatomy as a run does (label volumes and atlases read), solves its deformation
// and prints, for every simulated body, its organ, vertex and tet counts and the SHA-256 of its
// rest vertices, tets, organ of each tet and deformed vertices, so that tests can compare bodies
// built and solved in separate processes.
// Usage: body_fingerprint SCENE.yaml [ANATOMY_CACHE]   (the anatomy cache folder, as `phantasm run`
// uses it: the first process builds the anatomy, the others read it and mesh and solve the bodies)

#include "core/sha256.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <filesystem>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  using namespace phantasm;
  if (argc < 2 || argc > 3) {
    std::cerr << "usage: body_fingerprint SCENE.yaml [ANATOMY_CACHE]\n";
    return 2;
  }
  SceneLoadResult loaded = load_scene(argv[1]);
  if (!loaded.scene) {
    std::cerr << format_diagnostics(loaded.problems);
    return 2;
  }
  const Scene& scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  try {
    const Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy,
                                     argc == 3 ? std::filesystem::path(argv[2]) : std::filesystem::path())
                                .phantom;
    StageReport report;
    const PhantomDeformation deformation =
        deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    for (const DeformedBody& body : deformation.bodies) {
      std::string bytes;
      auto add = [&bytes](const void* data, std::size_t size) {
        bytes.append(static_cast<const char*>(data), size);
      };
      add(body.rest_mm.data(), static_cast<std::size_t>(body.rest_mm.size()) * sizeof(double));
      add(body.tets.data(), static_cast<std::size_t>(body.tets.size()) * sizeof(int));
      add(body.tet_organ.data(), body.tet_organ.size() * sizeof(int));
      add(body.deformed_mm.data(), static_cast<std::size_t>(body.deformed_mm.size()) * sizeof(double));
      std::cout << body.organ << ' ' << body.rest_mm.rows() << ' ' << body.tets.rows() << ' '
                << sha256_hex(bytes) << '\n';
    }
  } catch (const std::exception& error) {
    std::cerr << error.what() << '\n';
    return 1;
  }
  return 0;
}
