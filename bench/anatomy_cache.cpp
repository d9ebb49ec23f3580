// The anatomy stage of a scene alone, built or read from an anatomy cache, for whole-process
// timings: `time build/release/bench/anatomy_cache SCENE` builds it;
// `time build/release/bench/anatomy_cache SCENE DIR` reads it from DIR (and builds and stores
// it there the first time). Prints the organs and where they came from.
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"

#include <cstdio>
#include <iostream>

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s SCENE [CACHE_FOLDER]\n", argv[0]);
    return 2;
  }
  const phantasm::SceneLoadResult loaded = phantasm::load_scene(argv[1]);
  if (!loaded.scene) {
    std::cerr << phantasm::format_diagnostics(loaded.problems);
    return 2;
  }
  phantasm::Reporter reporter(std::cerr, phantasm::ProgressStyle::lines);
  const phantasm::Simulation simulation =
      phantasm::simulate(*loaded.scene, reporter, phantasm::SimulationStage::anatomy,
                         argc == 3 ? argv[2] : std::filesystem::path());
  std::printf("%zu organs\n", simulation.phantom.organs.size());
  return 0;
}
