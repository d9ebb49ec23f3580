// The outputs' profile (outputs.profile, docs/batch.md "Output profiles"): benchmark leaves out
// the organ meshes, previews, tissue fractions and parameter maps, and writes every file it
// keeps with the same bytes as the full profile.

#include "scene/scene.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <map>
#include <string>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// small-head.yaml with `keys` (YAML lines, two spaces in) added to its outputs section.
std::string with_outputs(const std::string& keys) {
  std::string text = read_file(k_small_scene);
  const std::string section = "outputs:\n";
  const std::size_t at = text.find(section);
  EXPECT_NE(at, std::string::npos) << k_small_scene << " has no outputs section";
  if (at != std::string::npos) text.insert(at + section.size(), keys);
  return text;
}

/// The outputs of small-head.yaml with `keys` added, parsed.
OutputSettings parsed_outputs(const std::string& keys) {
  const SceneLoadResult loaded = parse_scene(with_outputs(keys), k_small_scene);
  EXPECT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
  return loaded.scene ? loaded.scene->outputs : OutputSettings{};
}

/// What the benchmark profile leaves out: a file of a kind a registration benchmark never reads.
bool dropped_kind(const std::string& relative) {
  for (const char* part : {"/meshes/", "/previews/", "_probseg.", "map.nii.gz", "map.json", ".vdb"})
    if (relative.find(part) != std::string::npos) return true;
  return false;
}

/// What says how the run was made (its settings, log and report): these name the profile.
bool describes_the_run(const std::string& relative) {
  const std::string name = fs::path(relative).filename().string();
  return name == "provenance.json" || name == "log.txt" || name == "scene.yaml" ||
         fs::path(relative).extension() == ".html";
}

std::map<std::string, std::string> run_dataset(const std::string& keys, const std::string& name) {
  const fs::path folder = fresh_folder(name);
  const fs::path scene = folder / "scene.yaml";
  write_text_file(scene, with_outputs(keys));
  const CommandResult result =
      run_command({k_phantasm, "run", scene.string(), "-o", (folder / "out").string(), "-q"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  return result.exit_code == 0 ? folder_contents(folder / "out") : std::map<std::string, std::string>{};
}

} // namespace

// The profile sets the switches' defaults; a switch the scene gives wins over it.
TEST(OutputProfile, BenchmarkTurnsTheUnreadOutputsOffUnlessAskedFor) {
  const OutputSettings full = parsed_outputs("  profile: full\n");
  EXPECT_TRUE(full.meshes && full.previews && full.fractions && full.parameter_maps);
  const OutputSettings light = parsed_outputs("  profile: benchmark\n");
  EXPECT_EQ(light.profile, OutputProfile::benchmark);
  EXPECT_FALSE(light.meshes || light.previews || light.fractions || light.parameter_maps || light.vdb);
  EXPECT_TRUE(light.images && light.labels && light.displacement_fields && light.jacobian && light.landmarks);
  const OutputSettings asked = parsed_outputs("  profile: benchmark\n  meshes: true\n");
  EXPECT_TRUE(asked.meshes);
  EXPECT_FALSE(asked.previews);
  const SceneLoadResult bad = parse_scene(with_outputs("  profile: light\n"), k_small_scene);
  ASSERT_FALSE(bad.scene);
  const std::string message = format_diagnostics(bad.problems);
  EXPECT_NE(message.find("outputs.profile"), std::string::npos) << message;
  EXPECT_NE(message.find("light"), std::string::npos) << message;
}

// The small head run with each profile: the benchmark dataset holds none of the dropped kinds
// (which the full one holds), and each file it holds has the full dataset's bytes but those that
// describe the run.
TEST(OutputProfile, BenchmarkKeepsImagesLabelsFieldsAndLandmarksByteForByte) {
  const std::map<std::string, std::string> full = run_dataset("  profile: full\n", "profile-full");
  const std::map<std::string, std::string> light = run_dataset("  profile: benchmark\n", "profile-benchmark");
  std::map<std::string, int> kinds; // kept files per kind of the full dataset, all found below
  std::size_t dropped = 0;
  for (const auto& [relative, bytes] : full) {
    if (dropped_kind(relative)) {
      ++dropped;
      EXPECT_EQ(light.count(relative), 0u) << relative << " is written by the benchmark profile";
      continue;
    }
    ASSERT_EQ(light.count(relative), 1u) << relative << " is missing from the benchmark profile";
    if (describes_the_run(relative)) continue;
    EXPECT_TRUE(light.at(relative) == bytes) << relative << " differs between the profiles";
    for (const char* kind :
         {"_T1w.nii.gz", "_dseg.nii.gz", "_xfm.nii.gz", "_mask.nii.gz", "_jacobian.nii.gz", "_landmarks.csv"})
      if (relative.find(kind) != std::string::npos) ++kinds[kind];
  }
  EXPECT_GT(dropped, 20u) << "the full profile writes meshes, previews, fractions and maps";
  EXPECT_EQ(kinds.size(), 6u) << "images, labels, fields, masks, Jacobians and landmarks are compared";
  for (const auto& [relative, bytes] : light)
    EXPECT_EQ(full.count(relative), 1u) << relative << " is written by the benchmark profile only";
}
