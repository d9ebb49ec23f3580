// Costs a run pays before and after the stages: reading and validating a scene, and writing
// files atomically (temporary file, fsync, rename).

#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "scene/scene.hpp"

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace {

std::string head_scene_text() {
  std::ifstream stream(std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml");
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

void parse_and_validate_head_scene(benchmark::State& state) {
  const std::string text = head_scene_text();
  for (auto _ : state) {
    auto result = phantasm::parse_scene(text, "head.yaml");
    benchmark::DoNotOptimize(result);
  }
}
BENCHMARK(parse_and_validate_head_scene)->Unit(benchmark::kMicrosecond);

void sha256_throughput(benchmark::State& state) {
  const std::string bytes(static_cast<std::size_t>(state.range(0)), 'x');
  for (auto _ : state)
    benchmark::DoNotOptimize(phantasm::sha256_hex(bytes));
  state.SetBytesProcessed(state.iterations() * state.range(0));
}
BENCHMARK(sha256_throughput)->Arg(1 << 20);

void atomic_write(benchmark::State& state) {
  const std::string bytes(static_cast<std::size_t>(state.range(0)), 'x');
  const std::string path = "/tmp/phantasm-bench-atomic-" + std::to_string(::getpid()) + ".bin";
  for (auto _ : state)
    phantasm::write_file_atomically(path, bytes);
  state.SetBytesProcessed(state.iterations() * state.range(0));
  std::remove(path.c_str());
}
BENCHMARK(atomic_write)->Arg(4 << 10)->Arg(64 << 20)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
