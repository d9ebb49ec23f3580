// data-synthetic/colin-head.yaml end to end at 4 mm (small base meshes, one sequence, no
// k-space): its dataset, and its peak memory against the cost estimate (as the other scenes' in
// tests/apps/test_cost_estimate.cpp: one run of minutes serves both); and a bad label volume
// through the CLI.

#include "atlas/colin27_head.hpp"
#include "core/sha256.hpp"
#include "io/nifti_file.hpp"
#include "pipeline/cost_estimate.hpp"
#include "scene/scene.hpp"
#include "tests/support/coarse_runs.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace phantasm {
namespace {

namespace fs = std::filesystem;
using testing::dseg_table;
using testing::fresh_folder;
using testing::read_file;
using testing::run_command;
using testing::write_text_file;

const std::string k_phantasm = PHANTASM_EXECUTABLE;

TEST(ColinHeadScene, CoarseRunLabelsEveryOrganShiftsTheBrainAndMeetsItsCostEstimate) {
  if (!fs::is_directory(default_colin27_templates_dir())) GTEST_SKIP() << "mricron-data is not installed";
  // The measured run the task baselines and the registration study read too
  // (tests/support/coarse_runs.hpp); it built the anatomy.
  const testing::CoarseRun run = testing::shared_coarse_colin_run();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const SceneLoadResult loaded = load_scene(run.scene);
  ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
  const CostEstimate estimate = estimate_cost(*loaded.scene);
  const testing::MeasuredRun& measured = run.measured;
  // Peak memory within a factor of two of the estimate; processor time printed (it grows with the
  // machine's load; see tests/apps/test_cost_estimate.cpp).
  const double memory_ratio = estimate.peak_memory_bytes / measured.peak_bytes;
  std::printf(
      "colin-coarse: peak %.0f MB estimated / %.0f MB measured = %.2f; processor time %.2f s / %.2f s "
      "(wall %.2f s)\n",
      estimate.peak_memory_bytes / 1e6, measured.peak_bytes / 1e6, memory_ratio, estimate.cpu_seconds,
      measured.cpu_seconds, measured.wall_seconds);
  EXPECT_GT(memory_ratio, 0.5);
  EXPECT_LT(memory_ratio, 2.0);

  const fs::path derivatives = run.out / "derivatives" / "phantasm";
  const std::map<std::string, int> table = dseg_table(derivatives / "dseg.tsv");
  ImageGrid grid;
  const std::vector<std::int32_t> ref =
      read_nifti_labels(derivatives / "sub-01" / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz", &grid);
  const std::vector<std::int32_t> def =
      read_nifti_labels(derivatives / "sub-01" / "ses-def" / "anat" / "sub-01_ses-def_dseg.nii.gz", &grid);
  std::map<int, std::int64_t> count;
  for (const std::int32_t l : ref)
    ++count[l];
  for (const char* organ : {"scalp", "skull", "csf", "grey_matter", "white_matter", "ventricles",
                            "deep_grey_matter", "cerebellum", "brainstem"}) {
    ASSERT_TRUE(table.count(organ)) << organ;
    EXPECT_GT(count[table.at(organ)], 0) << organ << " has no voxel";
  }
  // The cortical grey matter's voxels against the source label (682.7 ml, docs/anatomy-colin27.md):
  // 4 mm voxels sample a 2-3 mm ribbon, so the bound is loose.
  const double voxel_ml = grid.spacing_mm.prod() / 1000.0;
  const double grey_ml = static_cast<double>(count[table.at("grey_matter")]) * voxel_ml;
  std::printf("grey_matter %.1f ml (source label 682.7 ml)\n", grey_ml);
  EXPECT_NEAR(grey_ml / 682.7, 1.0, 0.3);
  // The deformation moved the brain: labels changed and the provenance names the sources.
  std::int64_t changed = 0;
  for (std::size_t n = 0; n < ref.size(); ++n)
    changed += ref[n] != def[n];
  std::printf("voxels whose label changed: %ld\n", static_cast<long>(changed));
  EXPECT_GT(changed, 20);
  const std::string provenance = read_file(derivatives / "sub-01" / "provenance.json");
  // Physically sound, as every shipped scene (tests/apps/test_shipped_scenes.cpp): the solve
  // converged, no tet inverted, no NaN in any volume.
  const auto record = nlohmann::json::parse(provenance);
  EXPECT_TRUE(record.at("converged").get<bool>()) << record.at("solves").dump();
  ASSERT_FALSE(record.at("bodies").empty());
  for (const auto& body : record.at("bodies")) {
    EXPECT_EQ(body.at("inverted_tets").get<int>(), 0) << body.dump();
    EXPECT_GT(body.at("smallest_det_F").get<double>(), 0.0) << body.dump();
  }
  std::size_t volumes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(run.out)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || name.size() < 7 || name.substr(name.size() - 7) != ".nii.gz" ||
        name.find("_xfm") != std::string::npos)
      continue;
    ++volumes;
    const std::vector<double> values = read_nifti(entry.path()).values;
    EXPECT_TRUE(std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); }))
        << entry.path();
  }
  EXPECT_GT(volumes, 5u);
  EXPECT_NE(provenance.find("J Comput Assist Tomogr 1998; 22:324"), std::string::npos);
  EXPECT_NE(provenance.find("NeuroImage 2002; 15:273"), std::string::npos);
  EXPECT_NE(provenance.find("colin27 labels derived"), std::string::npos);
  // The simulated body, one conforming mesh of the real labels, has no sliver left: its log line
  // gives the smallest dihedral angle and the tets under 10 degrees after the repairs.
  const std::string log = read_file(derivatives / "sub-01" / "log.txt");
  std::smatch quality;
  ASSERT_TRUE(std::regex_search(
      log, quality,
      std::regex(R"(csf: one tet mesh[^\n]*min dihedral ([0-9.]+) deg, (\d+) tets under 10 deg)")))
      << log;
  std::printf("body: min dihedral %s deg, %s tets under 10 deg\n", quality[1].str().c_str(),
              quality[2].str().c_str());
  EXPECT_EQ(quality[2].str(), "0");
  EXPECT_GE(std::stod(quality[1].str()), 10.0);
}

// The outputs that speed work must not change: the coarse Colin head's label maps of both states
// and its exact map from the reference state to the deformed one, as values (not their compressed
// bytes), against the digests this program wrote when they were recorded. A change that moves a
// label or a field value fails here; one that means to (a new fit, a new model) records the new
// digests it prints, and its commit says why the outputs changed. The program is built for the
// baseline instruction set, its one run-time choice (the AVX2 lanes of the tet projection) gives
// the SSE2 lanes' bits, so every x86-64 machine with the project's Debian packages writes these.
TEST(ColinHeadScene, CoarseRunWritesTheLabelsAndTheFieldItWroteWhenRecorded) {
  if (!fs::is_directory(default_colin27_templates_dir())) GTEST_SKIP() << "mricron-data is not installed";
  const testing::CoarseRun run = testing::shared_coarse_colin_run();
  ASSERT_FALSE(::testing::Test::HasFailure());
  const fs::path subject = run.out / "derivatives" / "phantasm" / "sub-01";
  const auto labels_digest = [](const fs::path& path) {
    ImageGrid grid;
    const std::vector<std::int32_t> labels = read_nifti_labels(path, &grid);
    return sha256_hex(
        std::string_view(reinterpret_cast<const char*>(labels.data()), labels.size() * sizeof(std::int32_t)));
  };
  const auto values_digest = [](const fs::path& path) {
    const std::vector<double> values = read_nifti_vectors(path, 3).values;
    return sha256_hex(
        std::string_view(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double)));
  };
  const std::string ref = labels_digest(subject / "ses-ref" / "anat" / "sub-01_ses-ref_dseg.nii.gz");
  const std::string def = labels_digest(subject / "ses-def" / "anat" / "sub-01_ses-def_dseg.nii.gz");
  const std::string field = values_digest(subject / "xfm" / "sub-01_from-ref_to-def_mode-image_xfm.nii.gz");
  std::printf("reference labels %s\ndeformed labels %s\nfield from-ref_to-def %s\n", ref.c_str(), def.c_str(),
              field.c_str());
  EXPECT_EQ(ref, "961e4cdf19b6c486320197986ba5905727aab6deb9a8f617d7bbe55435d19833")
      << "the reference state's labels changed";
  EXPECT_EQ(def, "b304ebd59b65245509200697c29110fab1922a159bd8cad52d1ad393b108ab32")
      << "the deformed state's labels changed";
  EXPECT_EQ(field, "9b18800acb4458d626114cd583d0239121d1e1e8e0e1496061ef806f6220d05d")
      << "the field from the reference state to the deformed one changed";
}

// The intracranial body (csf and the organs nested in it, one conforming tet mesh meshed from the
// labels) is meshed and solved in two processes, as two runs of the scene sharing an anatomy cache
// would (the first builds the anatomy, the second reads it): the same vertices, tets, organ of
// each tet and deformed vertices, bit for bit. The coarse copy's surfaces are made smaller still
// (80 base triangles): the body is meshed from the labels, not from the surfaces; and its tets
// larger (10 mm, about 30 000 tets instead of 39 000 at 7 mm): the same meshing and solve, a
// third less of the second process's time.
TEST(ColinHeadScene, TheSimulatedBodyIsTheSameInEveryProcess) {
  if (!fs::is_directory(default_colin27_templates_dir())) GTEST_SKIP() << "mricron-data is not installed";
  const fs::path folder = fresh_folder("colin-head-body-fingerprint");
  const fs::path scene = folder / "colin-head.yaml";
  const std::string coarse =
      std::regex_replace(testing::coarse_colin_head_text(), std::regex(R"(base_mesh_triangles: \d+)"),
                         "base_mesh_triangles: 80");
  const std::string text = std::regex_replace(coarse, std::regex("tet_size_mm: 7"), "tet_size_mm: 10");
  ASSERT_NE(text, coarse) << "the coarse copy of colin-head.yaml no longer has tet_size_mm: 7";
  write_text_file(scene, text);
  const fs::path cache = folder / "anatomy-cache";
  const auto first = run_command({BODY_FINGERPRINT, scene.string(), cache.string()});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  // "csf <vertices> <tets> <sha256>": one body, a 10 mm mesh of about 30 000 tets.
  std::istringstream line(first.out);
  std::string organ, hash;
  long vertices = 0, tets = 0;
  ASSERT_TRUE(static_cast<bool>(line >> organ >> vertices >> tets >> hash)) << first.out;
  EXPECT_EQ(organ, "csf");
  EXPECT_GT(tets, 20000);
  EXPECT_EQ(hash.size(), 64u);
  ASSERT_FALSE(fs::is_empty(cache)) << "the first process kept no anatomy";
  const auto second = run_command({BODY_FINGERPRINT, scene.string(), cache.string()});
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(second.out, first.out);
}

TEST(ColinHeadScene, ALabelVolumeWithALabelOnItsEdgeIsABadInputAndNothingIsWritten) {
  const fs::path folder = fresh_folder("colin-head-scene-edge");
  ImageGrid grid;
  grid.dims = {20, 20, 20};
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-9.5, -9.5, -9.5);
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  for (int k = 0; k < 20; ++k)
    for (int j = 5; j < 15; ++j)
      for (int i = 5; i < 15; ++i)
        labels[voxel_index(grid.dims, i, j, k)] = 4;
  write_nifti_labels(folder / "bar.nii.gz", grid, labels);
  write_text_file(folder / "scene.yaml", "phantasm: 1\nname: bar\nseed: 1\nfield_strength_T: 3.0\n"
                                         "grid: {field_of_view_mm: 40, voxel_size_mm: 2}\n"
                                         "anatomy:\n  organs:\n"
                                         "    - {name: bar, tissue: csf, shape: {type: label_volume, "
                                         "file: bar.nii.gz, label: 4}}\n");
  const auto result =
      run_command({k_phantasm, "run", (folder / "scene.yaml").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("bar.nii.gz: label 4 (organ bar) touches the volume's edge"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("anatomy.organs[0].shape.label"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(folder / "out"));
}

} // namespace
} // namespace phantasm
