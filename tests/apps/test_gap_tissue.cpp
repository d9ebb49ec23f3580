// What fills the space a moved organ leaves inside a container that stays
// (docs/volumes-and-images.md, "The gap"): a ball pushed down inside a bone box.

#include "io/dataset_layout.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_gap_scene = k_source_dir / "tests" / "data" / "scenes" / "gap-ball.yaml";

// Labels of gap-ball.yaml: box 1, ball 2, pocket 3, the gap 4.
constexpr std::int32_t k_box = 1, k_ball = 2, k_pocket = 3, k_gap = 4;

struct GapRun {
  std::vector<std::int32_t> reference, deformed; ///< dseg
  std::vector<double> t2w;                       ///< deformed T2w image
  std::string table;                             ///< dseg.tsv
  DatasetLayout layout;
};

GapRun run_scene(const fs::path& scene, const std::string& name) {
  const fs::path out = fresh_folder(name) / "out";
  const CommandResult result = run_command({k_phantasm, "run", scene.string(), "-o", out.string(), "-q"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  GapRun run{{}, {}, {}, {}, DatasetLayout(out, "01")};
  run.reference = read_nifti_labels(run.layout.dseg(PhantomState::reference), nullptr);
  run.deformed = read_nifti_labels(run.layout.dseg(PhantomState::deformed), nullptr);
  run.t2w = read_nifti(run.layout.anat_image(PhantomState::deformed, "T2w")).values;
  run.table = read_file(run.layout.dseg_table());
  return run;
}

double mean_where(const std::vector<double>& image, const std::vector<std::int32_t>& labels,
                  std::int32_t label) {
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t v = 0; v < labels.size(); ++v) {
    if (labels[v] != label) continue;
    sum += image[v];
    ++count;
  }
  return count ? sum / static_cast<double>(count) : 0.0;
}

} // namespace

TEST(GapTissue, TheSpaceAMovedOrganLeavesIsCsfNotTheContainer) {
  const GapRun run = run_scene(k_gap_scene, "gap-csf");
  EXPECT_NE(run.table.find("4\tgap\tcsf\t"), std::string::npos) << run.table;
  std::size_t gap = 0, ball_to_box = 0, gap_at_rest = 0;
  for (std::size_t v = 0; v < run.deformed.size(); ++v) {
    gap += run.deformed[v] == k_gap;
    gap_at_rest += run.reference[v] == k_gap;
    ball_to_box += run.reference[v] == k_ball && run.deformed[v] == k_box;
    if (run.deformed[v] == k_gap) {
      EXPECT_EQ(run.reference[v], k_ball) << "voxel " << v;
    }
  }
  EXPECT_GT(gap, 20u); // a 6 mm dent under a 12 mm load region, 2 mm voxels
  EXPECT_EQ(gap_at_rest, 0u);
  // Only a few boundary voxels where the box's share beats both the ball's and the gap's.
  EXPECT_LT(ball_to_box, gap / 20) << "voxels the ball left labelled bone";
  // Spin echo TE 100 ms: the gap has CSF's signal (the pocket's, CSF too), far above bone's.
  const double in_gap = mean_where(run.t2w, run.deformed, k_gap);
  const double pocket = mean_where(run.t2w, run.deformed, k_pocket);
  EXPECT_NEAR(in_gap, pocket, 0.25 * pocket);
  EXPECT_GT(in_gap, 5.0 * mean_where(run.t2w, run.deformed, k_box));
  // The gap's fractions are CSF's: some gap voxels are whole CSF.
  const std::vector<double> csf = read_nifti(run.layout.probseg(PhantomState::deformed, "csf")).values;
  double largest_csf = 0.0;
  for (std::size_t v = 0; v < run.deformed.size(); ++v)
    if (run.deformed[v] == k_gap) largest_csf = std::max(largest_csf, csf[v]);
  EXPECT_NEAR(largest_csf, 1.0, 1e-6);
}

TEST(GapTissue, AnExplicitGapTissueOfAirLeavesNoSignal) {
  const fs::path scene = scene_variant(k_gap_scene, fresh_folder("gap-air-scene"), "  fixed: [box]\n",
                                       "  fixed: [box]\n  gap_tissue: air\n");
  const GapRun run = run_scene(scene, "gap-air");
  EXPECT_NE(run.table.find("4\tgap\tair\t"), std::string::npos) << run.table;
  std::size_t gap = 0;
  for (std::size_t v = 0; v < run.deformed.size(); ++v)
    gap += run.deformed[v] == k_gap;
  EXPECT_GT(gap, 20u);
  EXPECT_LT(mean_where(run.t2w, run.deformed, k_gap), 0.2 * mean_where(run.t2w, run.deformed, k_ball));
}
