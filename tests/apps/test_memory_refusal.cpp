// `phantasm run` and `batch` refuse, before any work, a scene whose estimated peak memory
// exceeds the memory available or --max-memory, naming the setting that drives it (#22); `info`
// prints each organ's effective settings and the estimate.

#include "core/error.hpp"
#include "pipeline/cost_estimate.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <regex>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// The small head with another voxel size.
fs::path small_head_with_voxels(const fs::path& folder, const std::string& voxel_mm) {
  std::string text = read_file(k_small_scene);
  text = std::regex_replace(text, std::regex("voxel_size_mm: 2.0"), "voxel_size_mm: " + voxel_mm);
  const fs::path scene = folder / "scene.yaml";
  write_text_file(scene, text);
  return scene;
}

} // namespace

TEST(MemoryRefusal, ATinyVoxelSizeIsRefusedAtOnceNamingItAndNothingIsWritten) {
  const fs::path folder = fresh_folder("refuse-voxels");
  // 0.1 mm voxels: 960 x 1120 x 1040 = 1.1e9 voxels (the scene allows 2^31), about 180 GB.
  const fs::path scene = small_head_with_voxels(folder, "0.1");
  const auto start = std::chrono::steady_clock::now();
  const CommandResult result =
      run_command({k_phantasm, "run", scene.string(), "-o", (folder / "out").string()});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("grid.voxel_size_mm 0.1 makes"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("estimated peak"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("available"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(folder / "out")) << "nothing may be written";
  EXPECT_LT(seconds, 5.0) << "refused before any work";
}

TEST(MemoryRefusal, MaxMemoryIsHonouredByRunAndBatch) {
  const fs::path folder = fresh_folder("refuse-max-memory");
  const CommandResult refused = run_command(
      {k_phantasm, "run", k_small_scene.string(), "-o", (folder / "out").string(), "--max-memory", "10M"});
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("(--max-memory)"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("estimated peak"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(folder / "out"));

  const CommandResult bad = run_command(
      {k_phantasm, "run", k_small_scene.string(), "-o", (folder / "out").string(), "--max-memory", "lots"});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--max-memory: expected a size"), std::string::npos) << bad.err;

  // A batch: the largest subject times the jobs that run at once.
  write_text_file(folder / "sweep.yaml", "phantasm_sweep: 1\nname: s\nbase_scene: " + k_small_scene.string() +
                                             "\nvary:\n  seed: [1, 2, 3]\n");
  const CostEstimate one = estimate_cost(*load_scene(k_small_scene).scene);
  const std::string between = std::to_string(static_cast<long>(1.5 * one.peak_memory_bytes));
  const CommandResult batch =
      run_command({k_phantasm, "batch", (folder / "sweep.yaml").string(), "-o", (folder / "batch").string(),
                   "--jobs", "2", "--max-memory", between});
  EXPECT_EQ(batch.exit_code, 2) << batch.err;
  EXPECT_NE(batch.err.find("x 2 jobs"), std::string::npos) << batch.err;
  EXPECT_NE(batch.err.find("or fewer --jobs"), std::string::npos) << batch.err;
  EXPECT_FALSE(fs::exists(folder / "batch" / "sub-001"));
}

TEST(MemoryRefusal, ARunWithinMaxMemoryRuns) {
  const fs::path folder = fresh_folder("allow-max-memory");
  const CommandResult allowed = run_command({k_phantasm, "run", k_small_scene.string(), "-o",
                                             (folder / "out").string(), "-q", "--max-memory", "64G"});
  EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
  const std::string log = read_file(folder / "out" / "derivatives" / "phantasm" / "sub-01" / "log.txt");
  EXPECT_EQ(log.rfind("[estimate] scalp: base size 80", 0), 0u) << "the log starts with the estimate:\n"
                                                                << log;
}

TEST(MemoryRefusal, InfoPrintsEachOrgansEffectiveSettingsAndTheEstimate) {
  const CommandResult result = run_command({k_phantasm, "info", k_small_scene.string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("grey_matter: base size 80 (the scene's), tets of"), std::string::npos)
      << result.out;
  EXPECT_NE(result.out.find("tessellation tolerance 0.5 mm"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("peak memory"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("processor time"), std::string::npos) << result.out;
}

TEST(MemoryRefusal, MemorySizesParse) {
  EXPECT_EQ(parse_memory_size("4G"), 4.0 * 1024 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("512M"), 512.0 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("2.5GB"), 2.5 * 1024 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("1GiB"), 1024.0 * 1024 * 1024);
  EXPECT_EQ(parse_memory_size("1000"), 1000.0);
  EXPECT_THROW(parse_memory_size("-1G"), InputError);
  EXPECT_THROW(parse_memory_size("4Q"), InputError);
  EXPECT_GT(available_memory_bytes(), 0.0);
}
