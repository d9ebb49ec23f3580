// The reference cache (pipeline/reference_cache.hpp): a stored reference state voxelizes the
// same bytes as building it, every input that shapes it reaches its key (and the deformed state's
// settings do not), runs with the cache cold, warm and without it write the same files, and a
// damaged entry is voxelized again.

#include "core/byte_codec.hpp"
#include "io/byte_compression.hpp"
#include "io/shape_files.hpp"
#include "pipeline/anatomy_cache.hpp"
#include "pipeline/reference_cache.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_small_head = fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "small-head.yaml";

void expect_same_volumes(const TissueVolumes& a, const TissueVolumes& b) {
  EXPECT_TRUE(a.labels == b.labels);
  EXPECT_TRUE(a.label_tissues == b.label_tissues);
  EXPECT_EQ(a.tissue_count, b.tissue_count);
  EXPECT_TRUE(a.partial_voxels == b.partial_voxels);
  // Bit for bit (a -0 is not a 0).
  ASSERT_EQ(a.partial_fractions.size(), b.partial_fractions.size());
  EXPECT_EQ(std::memcmp(a.partial_fractions.data(), b.partial_fractions.data(),
                        a.partial_fractions.size() * sizeof(float)),
            0);
  EXPECT_EQ(a.supersampled_voxels, b.supersampled_voxels);
}

} // namespace

// The state a deformed small head's voxelization built, stored and read back, gives the same
// volumes, fields and landmarks bit for bit; the volumes' own encoding too; the state built alone
// (voxelize_reference_state) is the same bytes.
TEST(ReferenceCache, DecodedStateVoxelizesTheSameBytes) {
  Scene scene = scene_of(k_small_head);
  scene.voxelization.keep_level_sets = true;
  Reporter quiet = Reporter::silent();
  const Simulation sim = simulate(scene, quiet, SimulationStage::deformation);
  ASSERT_TRUE(sim.deformed && sim.deformation);
  const auto voxelize = [&](std::optional<ReferenceVoxelization>* state, StageReport& report) {
    return voxelize_phantom(scene.voxelization, scene.organs, scene.grid.grid(), sim.phantom, &*sim.deformed,
                            &*sim.deformation, report, quiet, state);
  };
  std::optional<ReferenceVoxelization> built_state;
  StageReport built_report, read_report;
  const VoxelizedPhantom built = voxelize(&built_state, built_report);
  ASSERT_TRUE(built_state.has_value());
  ASSERT_FALSE(built_state->level_sets.empty());
  EXPECT_TRUE(built_state->volumes.labels.empty()); // they are the result's reference
  const std::string bytes = encode_reference_state(*built_state, built.reference);

  // The state built alone beforehand (a run builds it while the deformation is solved) is the
  // same state: the same bytes.
  const ReferenceVoxelization beforehand =
      voxelize_reference_state(scene.voxelization, scene.organs, scene.grid.grid(), sim.phantom);
  EXPECT_TRUE(encode_reference_state(beforehand, beforehand.volumes) == bytes);

  const auto voxels = static_cast<std::size_t>(scene.grid.grid().voxel_count());
  const std::size_t organs = sim.phantom.organs.size();
  std::optional<ReferenceVoxelization> read_state = decode_reference_state(bytes, voxels, organs);
  ASSERT_EQ(read_state->organs, built_state->organs);
  // Every value of every tree, the height bounds and the volumes: encoded again, the same bytes
  // (and an entry is a function of its state: shards and restarts store the same files).
  EXPECT_TRUE(encode_reference_state(*read_state, read_state->volumes) == bytes);
  EXPECT_TRUE(encode_reference_state(*built_state, built.reference) == bytes);
  for (std::size_t k = 0; k < built_state->level_sets.size(); ++k) {
    const LevelSet& a = *built_state->level_sets[k];
    const LevelSet& b = *read_state->level_sets[k];
    EXPECT_EQ(a.voxel_size_mm(), b.voxel_size_mm());
    EXPECT_EQ(a.half_width_mm(), b.half_width_mm());
    EXPECT_EQ(a.active_voxel_count(), b.active_voxel_count());
    const auto boxes_a = a.block_reach_mm(), boxes_b = b.block_reach_mm();
    ASSERT_EQ(boxes_a.size(), boxes_b.size());
    const LevelSet::Probe probe_a(a), probe_b(b);
    for (std::size_t box = 0; box < boxes_a.size(); box += 7) {
      EXPECT_TRUE(boxes_a[box].isApprox(boxes_b[box], 0.0));
      const Eigen::Vector3d x = boxes_a[box].center() + Eigen::Vector3d(0.3, -0.2, 0.1);
      EXPECT_EQ(probe_a(x), probe_b(x));
    }
  }
  ASSERT_EQ(read_state->height_ranges.size(), built_state->height_ranges.size());
  for (std::size_t o = 0; o < built_state->height_ranges.size(); ++o) {
    ASSERT_EQ(read_state->height_ranges[o].has_value(), built_state->height_ranges[o].has_value());
    if (!built_state->height_ranges[o]) continue;
    ASSERT_EQ(read_state->height_ranges[o]->size(), built_state->height_ranges[o]->size());
    for (std::size_t t = 0; t < built_state->height_ranges[o]->size(); ++t) {
      EXPECT_EQ((*read_state->height_ranges[o])[t].lowest, (*built_state->height_ranges[o])[t].lowest);
      EXPECT_EQ((*read_state->height_ranges[o])[t].highest, (*built_state->height_ranges[o])[t].highest);
    }
  }

  // The deepest points' candidates go with the state; the landmarks picked from them are those
  // the labels give when read again (voxelize_phantom's map and tolerance).
  ASSERT_TRUE(built_state->deepest_candidates.has_value());
  ASSERT_TRUE(read_state->deepest_candidates.has_value());
  ASSERT_EQ(read_state->deepest_candidates->size(), organs);
  std::size_t candidates = 0;
  for (std::size_t o = 0; o < organs; ++o) {
    EXPECT_TRUE((*read_state->deepest_candidates)[o] == (*built_state->deepest_candidates)[o]);
    candidates += (*read_state->deepest_candidates)[o].size();
  }
  EXPECT_GT(candidates, organs); // more than one an organ: the ones a map may need after the first
  const ImageGrid grid = scene.grid.grid();
  const DeformationMap map(sim.deformation->bodies, 2.0 * grid.spacing_mm.maxCoeff(), sim.deformation->head);
  const std::vector<Landmark> from_labels =
      organ_landmarks(sim.phantom, &*sim.deformation, &map, std::clamp(grid.spacing_mm.minCoeff(), 0.5, 2.0),
                      nullptr, {}, {&grid, &built.reference.labels});
  ASSERT_EQ(from_labels.size(), built.landmarks.size());
  for (std::size_t l = 0; l < built.landmarks.size(); ++l) {
    EXPECT_EQ(from_labels[l].reference_mm, built.landmarks[l].reference_mm) << from_labels[l].name;
    EXPECT_EQ(from_labels[l].deformed_mm, built.landmarks[l].deformed_mm) << from_labels[l].name;
  }

  const VoxelizedPhantom read = voxelize(&read_state, read_report);
  EXPECT_FALSE(read_state.has_value()); // taken
  expect_same_volumes(read.reference, built.reference);
  ASSERT_TRUE(read.deformed && built.deformed);
  expect_same_volumes(*read.deformed, *built.deformed);
  ASSERT_TRUE(read.motion && built.motion);
  EXPECT_TRUE(read.motion->ref_to_def == built.motion->ref_to_def);
  EXPECT_TRUE(read.motion->def_to_ref == built.motion->def_to_ref);
  EXPECT_TRUE(read.motion->jacobian == built.motion->jacobian);
  ASSERT_EQ(read.landmarks.size(), built.landmarks.size());
  for (std::size_t l = 0; l < built.landmarks.size(); ++l) {
    EXPECT_EQ(read.landmarks[l].reference_mm, built.landmarks[l].reference_mm);
    EXPECT_EQ(read.landmarks[l].deformed_mm, built.landmarks[l].deformed_mm);
  }
  EXPECT_EQ(read_report.modelled, built_report.modelled);
  ASSERT_EQ(read.reference_level_sets.size(), built.reference_level_sets.size());
  ASSERT_EQ(read.deformed_level_sets.size(), built.deformed_level_sets.size());

  // The volumes' encoding alone; bytes cut short are refused, not misread.
  const std::string volume_bytes = encode_tissue_volumes(built.reference);
  expect_same_volumes(decode_tissue_volumes(volume_bytes), built.reference);
  EXPECT_THROW(decode_tissue_volumes(volume_bytes.substr(0, volume_bytes.size() - 1)), DamagedBytes);
  EXPECT_THROW(decode_reference_state(bytes.substr(0, bytes.size() / 2), voxels, organs), DamagedBytes);
  EXPECT_THROW(decode_reference_state(bytes.substr(0, 100), voxels, organs), DamagedBytes);
  // The deepest-point candidates come last: an entry cut inside them, or whose flag for them is
  // neither 0 nor 1, is refused too.
  EXPECT_THROW(decode_reference_state(bytes.substr(0, bytes.size() - 1), voxels, organs), DamagedBytes);
  std::string bad_flag = bytes;
  const std::size_t flag_at = bytes.size() - [&] {
    std::size_t tail = sizeof(std::uint64_t); // the organ count
    for (const auto& own : *built_state->deepest_candidates)
      tail += 2 * sizeof(std::int64_t) + own.size() * 3 * sizeof(double);
    return tail + 1;
  }();
  ASSERT_EQ(bad_flag[flag_at], '\1');
  bad_flag[flag_at] = '\2';
  EXPECT_THROW(decode_reference_state(bad_flag, voxels, organs), DamagedBytes);
  // A whole state that does not fit the run (another grid, another phantom) is refused too: it is
  // voxelized again instead of reaching voxelize_phantom, which would stop the run.
  EXPECT_THROW(decode_reference_state(bytes, voxels + 1, organs), DamagedBytes);
  EXPECT_THROW(decode_reference_state(bytes, voxels, organs + 1), DamagedBytes);
  EXPECT_THROW(decode_reference_state(bytes, voxels, static_cast<std::size_t>(read_state->organs.back())),
               DamagedBytes);
}

// A change of anything the reference state is made from gives another key; a change of what
// only the deformed state or the outputs read keeps it (those subjects share the entry).
TEST(ReferenceCache, EveryInputOfTheReferenceStateChangesTheKey) {
  const Scene scene = scene_of(k_small_head);
  const std::string anatomy_key = anatomy_cache_key(scene.anatomy, {});
  ASSERT_EQ(anatomy_key.size(), 64u) << "no build id: the cache would be off";
  struct Inputs {
    std::string anatomy_key;
    VoxelizationSettings settings;
    AnatomySettings anatomy; // its organ table
    ImageGrid grid;
  };
  const Inputs base{anatomy_key, scene.voxelization, scene.anatomy, scene.grid.grid()};
  ASSERT_GE(base.settings.organ_bounds_mm.size(), 2u);
  ASSERT_TRUE(base.settings.organ_bounds_mm[1].has_value());
  const auto key_of = [](const Inputs& in) {
    return reference_cache_key(in.anatomy_key, in.settings, organ_table(in.anatomy), in.grid);
  };
  using Change = std::function<void(Inputs&)>;
  const std::vector<Change> changes = {
      [](Inputs& in) { in.anatomy_key[0] = in.anatomy_key[0] == '0' ? '1' : '0'; },
      [](Inputs& in) { in.grid.dims.x() += 1; },
      [](Inputs& in) { in.grid.spacing_mm.y() *= 1.0 + 1e-12; },
      [](Inputs& in) { in.grid.world_from_voxel(0, 3) += 1e-9; },
      [](Inputs& in) { in.grid.world_from_voxel(1, 0) += 1e-9; },
      [](Inputs& in) { in.settings.supersampling += 1; },
      [](Inputs& in) { in.settings.tessellation_tolerance_mm *= 2.0; },
      [](Inputs& in) {
        in.settings.level_sets_from_tessellation = !in.settings.level_sets_from_tessellation;
      },
      [](Inputs& in) { in.settings.organ_bounds_mm[1]->min_mm.z() -= 1e-9; },
      [](Inputs& in) { in.settings.organ_bounds_mm[1]->max_mm.x() += 1e-9; },
      [](Inputs& in) { in.settings.organ_bounds_mm[1].reset(); },
      [](Inputs& in) { in.settings.organ_bounds_mm.pop_back(); },
      [](Inputs& in) { in.anatomy.organs[1].name += "x"; },
      [](Inputs& in) { in.anatomy.organs[1].tissue += "x"; },
      [](Inputs& in) { in.anatomy.organs[2].inside = in.anatomy.organs[0].name; }, // another depth
      [](Inputs& in) { in.anatomy.organs.pop_back(); },
  };
  expect_every_change_changes_the_key<Inputs>(base, changes, key_of);
  const std::string base_key = key_of(base);
  const std::vector<Change> kept = {
      [](Inputs& in) { in.settings.gap_tissue = "csf"; },
      [](Inputs& in) { in.settings.gap_fill = "csf"; },
      [](Inputs& in) { in.settings.deformed = !in.settings.deformed; },
      [](Inputs& in) { in.settings.keep_level_sets = !in.settings.keep_level_sets; },
      [](Inputs& in) { in.settings.labels = !in.settings.labels; },
      [](Inputs& in) { in.settings.fractions = !in.settings.fractions; },
      [](Inputs& in) { in.settings.displacement_fields = !in.settings.displacement_fields; },
      [](Inputs& in) { in.settings.jacobian = !in.settings.jacobian; },
      [](Inputs& in) { in.settings.landmarks = !in.settings.landmarks; },
  };
  for (std::size_t c = 0; c < kept.size(); ++c) {
    Inputs changed = base;
    kept[c](changed);
    EXPECT_EQ(key_of(changed), base_key) << "kept " << c;
  }
  EXPECT_TRUE(reference_cache_key("", base.settings, organ_table(base.anatomy), base.grid).empty());
}

// Runs of the small head without the cache, with it cold (stores the entry) and warm (reads it)
// write the same bytes in every file; the cold and warm logs and provenance are the same too,
// and name the entry. A damaged entry is voxelized again (a line, no stage warning) and stored anew.
TEST(ReferenceCache, RunsWithTheCacheColdWarmAndWithoutWriteTheSameFiles) {
  const Scene scene = scene_of(k_small_head);
  const fs::path folder = fresh_folder("reference-cache");
  const fs::path cache = folder / "cache";
  const auto run = [&](const std::string& name, const fs::path& cache_folder) {
    RunOptions options;
    options.output = folder / name;
    options.anatomy_cache = cache_folder;
    Reporter quiet = Reporter::silent();
    const RunSummary summary = run_scene(scene, options, quiet);
    return std::make_pair(summary, files_of(summary, options.output));
  };
  const auto [none_summary, none] = run("none", {});
  const auto [cold_summary, cold] = run("cold", cache);
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(cache))
    if (entry.path().filename().string().rfind("reference-", 0) == 0 && entry.path().extension() == ".bin")
      entries.push_back(entry.path());
  ASSERT_EQ(entries.size(), 1u);
  const auto [warm_summary, warm] = run("warm", cache);
  ASSERT_GT(none.size(), 50u);
  ASSERT_EQ(cold.size(), none.size());
  ASSERT_EQ(warm.size(), none.size());
  for (const auto& [path, bytes] : none) {
    SCOPED_TRACE(path);
    ASSERT_TRUE(cold.count(path) && warm.count(path));
    EXPECT_TRUE(cold.at(path) == warm.at(path));
    if (is_record(path)) {
      if (is_page_summary(path)) continue;
      EXPECT_EQ(bytes.find("kept in the reference cache as entry"), std::string::npos);
      EXPECT_NE(cold.at(path).find("kept in the reference cache as entry"), std::string::npos);
      continue;
    }
    EXPECT_TRUE(cold.at(path) == bytes);
  }
  EXPECT_TRUE(contains(warm_summary.stages[2].modelled, "kept in the reference cache as entry"));

  // Read without the stage (as a run reads it while the deformation is solved): the stored state.
  const std::string stored = read_file(entries[0]);
  const std::size_t stored_header = stored.find('\n', stored.find('\n') + 1) + 1;
  const std::string state_bytes = decompress_bytes(std::string_view(stored).substr(stored_header));
  const std::string anatomy_key =
      anatomy_cache_key(scene.anatomy, read_shape_files(scene.anatomy, {}, scene.grid.grid()));
  const auto read_alone = [&] {
    return read_stored_reference_state(anatomy_key, scene.voxelization, scene.organs, scene.grid.grid(),
                                       scene.organs.size(), cache);
  };
  const std::optional<ReferenceVoxelization> alone = read_alone();
  ASSERT_TRUE(alone.has_value());
  EXPECT_TRUE(encode_reference_state(*alone, alone->volumes) == state_bytes);
  write_text_file(entries[0], stored.substr(0, stored.size() - 100));
  EXPECT_FALSE(read_alone().has_value()); // damaged: left to the stage, which says so
  const auto [damaged_summary, damaged] = run("damaged", cache);
  EXPECT_TRUE(contains(damaged_summary.stages[2].modelled, "a damaged reference cache entry"));
  EXPECT_TRUE(
      damaged_summary.stages[2].warnings.empty()); // voxelized again soundly: --strict has nothing to refuse
  for (const auto& [path, bytes] : none) {
    if (is_record(path)) continue;
    EXPECT_TRUE(damaged.at(path) == bytes) << path;
  }
  // Stored anew, whole: after its two header lines (format, key), the state.
  const std::string restored = read_file(entries[0]);
  const std::size_t header = restored.find('\n', restored.find('\n') + 1) + 1;
  EXPECT_NO_THROW(decode_reference_state(decompress_bytes(std::string_view(restored).substr(header)),
                                         static_cast<std::size_t>(scene.grid.grid().voxel_count()),
                                         scene.organs.size()));
}
