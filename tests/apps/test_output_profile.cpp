// The outputs' profile (outputs.profile, docs/batch.md "Output profiles"): benchmark leaves out
// the organ meshes (but the solved bodies' tet meshes), previews, tissue fractions and parameter
// maps, and writes every file it keeps with the same bytes as the full profile.

#include "io/dataset_layout.hpp"
#include "scene/scene.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <set>
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

/// The file names' ends of the solved bodies' tet meshes, as the provenance.json files of a
/// dataset's subjects list the bodies: every profile writes them (phantasm pair composes through
/// them).
std::set<std::string> body_tet_meshes(const fs::path& dataset) {
  std::set<std::string> ends;
  for (const auto& entry : fs::recursive_directory_iterator(dataset)) {
    if (entry.path().filename() != "provenance.json") continue;
    const nlohmann::json provenance = nlohmann::json::parse(read_file(entry.path()));
    for (const auto& body : provenance.at("bodies"))
      ends.insert("_organ-" + bids_entity_value(body.at("organ").get<std::string>()) + "_tetmesh.vtu");
  }
  return ends;
}

/// What the benchmark profile leaves out: a file of a kind a registration benchmark never reads.
bool dropped_kind(const std::string& relative, const std::set<std::string>& bodies) {
  for (const std::string& end : bodies)
    if (relative.size() > end.size() && relative.compare(relative.size() - end.size(), end.size(), end) == 0)
      return false;
  for (const char* part : {"/meshes/", "/previews/", "_probseg.", "map.nii.gz", "map.json", ".vdb"})
    if (relative.find(part) != std::string::npos) return true;
  return false;
}

/// What says how the run was made (its settings, log and report, and the dataset page's summary,
/// which names the provenance.json): these name the profile.
bool describes_the_run(const std::string& relative) {
  const std::string name = fs::path(relative).filename().string();
  return name == "provenance.json" || name == "log.txt" || name == "scene.yaml" ||
         name == "page-summary.json" || fs::path(relative).extension() == ".html";
}

/// Runs small-head.yaml with `keys` in its outputs into a fresh folder: the files written, and in
/// `bodies` (when given) the ends of the solved bodies' tet meshes' names.
std::map<std::string, std::string> run_dataset(const std::string& keys, const std::string& name,
                                               std::set<std::string>* bodies = nullptr) {
  const fs::path folder = fresh_folder(name);
  const fs::path scene = folder / "scene.yaml";
  write_text_file(scene, with_outputs(keys));
  const CommandResult result =
      run_command({k_phantasm, "run", scene.string(), "-o", (folder / "out").string(), "-q"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  if (bodies && result.exit_code == 0) *bodies = body_tet_meshes(folder / "out");
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
  std::set<std::string> bodies;
  const std::map<std::string, std::string> full = run_dataset("  profile: full\n", "profile-full", &bodies);
  const std::map<std::string, std::string> light = run_dataset("  profile: benchmark\n", "profile-benchmark");
  std::map<std::string, int> kinds; // kept files per kind of the full dataset, all found below
  std::size_t dropped = 0;
  EXPECT_FALSE(bodies.empty()) << "the small head has a solved body";
  for (const auto& [relative, bytes] : full) {
    if (dropped_kind(relative, bodies)) {
      ++dropped;
      EXPECT_EQ(light.count(relative), 0u) << relative << " is written by the benchmark profile";
      continue;
    }
    ASSERT_EQ(light.count(relative), 1u) << relative << " is missing from the benchmark profile";
    if (describes_the_run(relative)) continue;
    EXPECT_TRUE(light.at(relative) == bytes) << relative << " differs between the profiles";
    for (const char* kind : {"_T1w.nii.gz", "_dseg.nii.gz", "_xfm.nii.gz", "_mask.nii.gz", "_jacobian.nii.gz",
                             "_landmarks.csv", "_tetmesh.vtu"})
      if (relative.find(kind) != std::string::npos) ++kinds[kind];
  }
  EXPECT_GT(dropped, 20u) << "the full profile writes meshes, previews, fractions and maps";
  EXPECT_EQ(kinds.size(), 7u)
      << "images, labels, fields, masks, Jacobians, landmarks and the bodies' tet meshes are compared";
  for (const auto& [relative, bytes] : light)
    EXPECT_EQ(full.count(relative), 1u) << relative << " is written by the benchmark profile only";
}
