// A population sweep's subjects: each subject's drawn volume changes, solved by the deformation
// stage from the shared template, are what its organs' tets reach (within 1 %, absolute).

#include "anatomy/phantom.hpp"
#include "batch/sweep.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/support/deformed_bodies.hpp"

#include <gtest/gtest.h>

#include <map>

using namespace phantasm;

using phantasm::testing::organ_volume_changes;

// Three subjects of tests/data/sweeps/population-balls.yaml: the template is built once, each
// subject's drawn changes (both balls) are solved from it, and each ball's tets end within 0.01 of
// the subject's draw; the draws differ between subjects by more than that, so a subject solved
// with another's values would fail.
TEST(PopulationSweep, EachSubjectsMeasuredVolumeChangesMatchItsDraws) {
  const Sweep sweep =
      load_sweep(std::string(PHANTASM_SOURCE_DIR) + "/tests/data/sweeps/population-balls.yaml");
  ASSERT_EQ(sweep.subjects.size(), 3u);
  Reporter quiet = Reporter::silent();
  std::vector<std::map<std::string, double>> drawn;
  for (const SweepSubject& subject : sweep.subjects) {
    ASSERT_EQ(subject.values.size(), 2u);
    drawn.push_back(
        {{"left", std::stod(subject.values[0].second)}, {"right", std::stod(subject.values[1].second)}});
  }
  const SceneLoadResult first = parse_scene(sweep.subjects[0].scene_text, sweep.base_scene);
  ASSERT_TRUE(first.scene) << format_diagnostics(first.problems);
  const Phantom phantom = build_phantom(first.scene->anatomy, {}, quiet);
  for (std::size_t s = 0; s < sweep.subjects.size(); ++s) {
    const SceneLoadResult loaded = parse_scene(sweep.subjects[s].scene_text, sweep.base_scene);
    ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
    StageReport report;
    const PhantomDeformation d =
        deform_phantom(loaded.scene->deformation, loaded.scene->organs, phantom, report, quiet);
    ASSERT_EQ(d.bodies.size(), 1u);
    EXPECT_EQ(d.bodies[0].inverted_tets, 0);
    const std::map<std::string, double> measured = organ_volume_changes(d, loaded.scene->organs);
    for (const char* organ : {"left", "right"}) {
      EXPECT_NEAR(measured.at(organ), drawn[s].at(organ), 0.01)
          << "sub-" << sweep.subjects[s].id << " " << organ;
      for (std::size_t other = 0; other < drawn.size(); ++other) {
        if (other != s) {
          EXPECT_GT(std::abs(drawn[other].at(organ) - drawn[s].at(organ)), 0.02)
              << "the fixture's draws must tell subjects apart";
        }
      }
    }
  }
}
