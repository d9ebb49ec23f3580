// Sweep files: grid order and counts, seeded random draws that do not depend on the shard, key
// paths into nested mappings and lists, the special keys, shards, and clear messages.

#include "batch/sweep.hpp"
#include "core/error.hpp"
#include "scene/scene.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_base = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "small-head.yaml";

Sweep sweep_of(const std::string& name, const std::string& vary, const std::string& extra = "") {
  const fs::path folder = fresh_folder("sweep-" + name);
  write_text_file(folder / "sweep.yaml", "phantasm_sweep: 1\nbase_scene: " + k_base.string() + "\nseed: 9\n" +
                                             extra + "vary:\n" + vary);
  return load_sweep(folder / "sweep.yaml");
}

Scene scene_of(const SweepSubject& subject) {
  SceneLoadResult loaded = parse_scene(subject.scene_text, k_base);
  EXPECT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
  return *loaded.scene;
}

} // namespace

TEST(Sweep, ListsFormAGridWithTheLastKeyFastestAndRepeats) {
  const Sweep sweep = sweep_of("grid",
                               "  acquisition.noise_percent: [1, 2, 3]\n"
                               "  acquisition.bias_percent: [0, 10]\n",
                               "repeats: 2\n");
  ASSERT_EQ(sweep.subjects.size(), 12u);
  EXPECT_EQ(sweep.subjects[0].id, "01");
  EXPECT_EQ(sweep.subjects[11].id, "12");
  const double expected_noise[] = {1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3};
  const double expected_bias[] = {0, 0, 10, 10, 0, 0, 10, 10, 0, 0, 10, 10};
  for (std::size_t s = 0; s < 12; ++s) {
    const Scene scene = scene_of(sweep.subjects[s]);
    EXPECT_EQ(scene.mri.acquisition.noise_percent, expected_noise[s]) << s;
    EXPECT_EQ(scene.mri.acquisition.bias_percent, expected_bias[s]) << s;
    EXPECT_EQ(scene.outputs.subject, sweep.subjects[s].id);
  }
  EXPECT_EQ(
      participants_tsv(sweep).substr(0, 100),
      "participant_id\tacquisition.noise_percent\tacquisition.bias_percent\nsub-01\t1\t0\nsub-02\t1\t0\nsub-"
      "03\t1\t10\n");
}

TEST(Sweep, RandomDrawsAreSeededPerSubjectAndInRange) {
  const std::string vary = "  seed: {random_integer: [1, 1000]}\n"
                           "  materials.brain.youngs_modulus_Pa: {log_uniform: [1000, 10000]}\n"
                           "  acquisition.noise_percent: [1, 2]\n";
  const Sweep a = sweep_of("random-a", vary, "repeats: 3\n");
  const Sweep b = sweep_of("random-b", vary, "repeats: 3\n");
  ASSERT_EQ(a.subjects.size(), 6u);
  std::set<std::uint64_t> seeds;
  for (std::size_t s = 0; s < 6; ++s) {
    EXPECT_EQ(a.subjects[s].scene_text, b.subjects[s].scene_text);
    const Scene scene = scene_of(a.subjects[s]);
    EXPECT_GE(scene.seed, 1u);
    EXPECT_LE(scene.seed, 1000u);
    seeds.insert(scene.seed);
    double e = 0.0;
    for (const auto& material : scene.deformation.materials)
      if (material.name == "brain") e = material.youngs_modulus_Pa;
    EXPECT_GE(e, 1000.0);
    EXPECT_LE(e, 10000.0);
  }
  EXPECT_GE(seeds.size(), 5u);
  const Sweep other = sweep_of("random-c", vary, "repeats: 3\nname: x\n");
  EXPECT_EQ(other.subjects[0].scene_text, a.subjects[0].scene_text); // the seed, not the name, draws
}

TEST(Sweep, KeyPathsReachListsAndTheSpecialKeysScaleAndSelect) {
  const Sweep sweep = sweep_of("paths", "  deformation.loads[0].region.radius_mm: [20]\n"
                                        "  deformation.scale: [2]\n"
                                        "  sequences: [[T2w]]\n"
                                        "  acquisition.coils: [4]\n");
  ASSERT_EQ(sweep.subjects.size(), 1u);
  const Scene scene = scene_of(sweep.subjects[0]);
  ASSERT_EQ(scene.deformation.loads.size(), 1u);
  EXPECT_EQ(scene.deformation.loads[0].region_radius_mm, 20.0);
  EXPECT_TRUE(scene.deformation.loads[0].displacement_mm.isApprox(Eigen::Vector3d(-4, 0, -6)));
  ASSERT_EQ(scene.mri.sequences.size(), 1u);
  EXPECT_EQ(scene.mri.sequences[0].name, "T2w");
  EXPECT_EQ(scene.mri.acquisition.coils, 4);
}

TEST(Sweep, ShardsSplitTheSubjectsDisjointly) {
  const Shard first = parse_shard("1/3"), third = parse_shard("3/3");
  EXPECT_TRUE(first.holds(0));
  EXPECT_TRUE(first.holds(3));
  EXPECT_FALSE(first.holds(2));
  EXPECT_TRUE(third.holds(2));
  for (const char* bad : {"0/3", "4/3", "1", "a/b", "1/0"})
    EXPECT_THROW(parse_shard(bad), InputError) << bad;
}

TEST(Sweep, MistakesAreNamedWithTheirLine) {
  EXPECT_NE(input_error_message([] {
              sweep_of("bad-kind", "  seed: {gaussian: [1, 2]}\n");
            }).find("sweep.yaml:5:9: vary.seed: expected a list of values or one of {uniform: [a, b]}"),
            std::string::npos);
  EXPECT_NE(
      input_error_message([] { sweep_of("bad-index", "  deformation.loads[3].organ: [x]\n"); })
          .find("vary.deformation.loads[3].organ: expected list element [3] of 'loads' in the base scene, "
                "found 1 elements"),
      std::string::npos);
  const std::string invalid =
      input_error_message([] { sweep_of("bad-scene", "  acquisition.noise_percent: [5, 500]\n"); });
  EXPECT_NE(invalid.find("subject 02 (acquisition.noise_percent = 500) gives a scene that does not validate"),
            std::string::npos)
      << invalid;
  EXPECT_NE(invalid.find("acquisition.noise_percent"), std::string::npos);
  // The subject's scene is emitted anew: its problems are placed where the user wrote the value,
  // at the varied key in the sweep or at the key in the base scene, not at lines of that text.
  EXPECT_NE(invalid.find("/sweep.yaml:5:30: acquisition.noise_percent: expected"), std::string::npos)
      << invalid;
  const std::string scaled =
      input_error_message([] { sweep_of("bad-scale", "  deformation.scale: [1, 1000]\n"); });
  EXPECT_NE(scaled.find(k_base.string() +
                        ":48:25: deformation.loads[0].displacement_mm[0]: expected a number in mm in "
                        "[-1000, 1000], found '-2000'"),
            std::string::npos)
      << scaled;
  EXPECT_NE(input_error_message([] {
              sweep_of("bad-top", "  seed: [1]\n", "jobs: 2\n");
            }).find("jobs: expected one of phantasm_sweep, name, base_scene, seed, repeats, vary"),
            std::string::npos);
}

// yaml-cpp 0.7 reads a ',' where a document starts as endless empty documents; the sweep and its
// base scene are refused at the comma instead (found by fuzz/fuzz_sweep.cpp).
TEST(Sweep, AStrayCommaWhereTheSweepStartsIsASyntaxError) {
  const fs::path folder = fresh_folder("sweep-stray-comma");
  write_text_file(folder / "sweep.yaml", "# sweep\n, phantasm_sweep: 1\n");
  EXPECT_EQ(input_error_message([&] { load_sweep(folder / "sweep.yaml"); }),
            (folder / "sweep.yaml").string() +
                ":2:1: sweep: expected valid YAML, found unexpected ',' where a value or a key should start");
  write_text_file(folder / "base.yaml", ", phantasm: 1\n");
  write_text_file(folder / "sweep.yaml", "phantasm_sweep: 1\nbase_scene: base.yaml\nvary:\n  seed: [1, 2]\n");
  EXPECT_EQ(input_error_message([&] { load_sweep(folder / "sweep.yaml"); }),
            (folder / "base.yaml").string() +
                ":1:1: expected valid YAML, found unexpected ',' where a value or a key should start");
}
