// Costs a run pays before and after the stages: reading and validating a scene, writing files
// atomically (temporary file, fsync, rename), and reading a compressed field back (a subject's
// page, a pair, an evaluation).

#include "core/sha256.hpp"
#include "io/atomic_file.hpp"
#include "io/nifti_file.hpp"
#include "scene/scene.hpp"

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
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

/// A displacement field of the population's grid (208 x 240 x 200 voxels, 3 components of
/// float32, 120 MB; smooth, so about 20 MB gzipped as our writer writes it) read back, its gzip
/// members inflated whole by libdeflate (argument 1) or through zlib's stream (0).
void read_compressed_field(benchmark::State& state) {
  phantasm::ImageGrid grid;
  grid.dims = {208, 240, 200};
  const auto voxels = static_cast<std::size_t>(grid.voxel_count());
  std::vector<float> field(3 * voxels);
  for (std::size_t n = 0; n < field.size(); ++n) {
    const double x = static_cast<double>(n % 208), y = static_cast<double>(n / 208 % 240);
    field[n] =
        static_cast<float>(2.0 * std::sin(0.05 * x) * std::cos(0.04 * y) + 1e-3 * static_cast<double>(n % 7));
  }
  const std::string path = "/tmp/phantasm-bench-field-" + std::to_string(::getpid()) + ".nii.gz";
  phantasm::write_nifti(path, grid, field, {phantasm::NiftiIntent::displacement, 3, "field"});
  phantasm::set_whole_member_reads_for_testing(state.range(0) != 0);
  for (auto _ : state)
    benchmark::DoNotOptimize(phantasm::read_nifti_vectors(path));
  phantasm::set_whole_member_reads_for_testing(true);
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(field.size() * sizeof(float)));
  std::remove(path.c_str());
}
BENCHMARK(read_compressed_field)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
