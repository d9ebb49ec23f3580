// Growth and atrophy of atlas regions (`{type: growth, region: ..., atlas: aal}`): the regions
// and groups a scene names resolved to the AAL labels, misnamed or twice-prescribed regions
// refused at their scene key before any work, and the prescribed change of each region's volume
// measured in the result, on the deformed tets and from the Jacobian of the ground-truth field.

#include "atlas/atlas_regions.hpp"
#include "atlas/colin27_head.hpp"
#include "core/error.hpp"
#include "pipeline/run_pipeline.hpp"
#include "sim/growth_regions.hpp"
#include "tests/support/deformed_bodies.hpp"
#include "tests/support/files.hpp"
#include "tests/support/subprocess.hpp"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

using namespace phantasm;
namespace fs = std::filesystem;

namespace {

const std::string k_scene = "tests/data/scenes/growth-region.yaml";

std::shared_ptr<const RegionAtlas> aal() {
  static const std::shared_ptr<const RegionAtlas> atlas = [] {
    AtlasRegions read = read_atlas_regions("aal", default_colin27_templates_dir());
    auto result = std::make_shared<RegionAtlas>();
    result->name = "aal";
    result->source = read.source;
    result->grid = read.grid;
    result->labels = std::move(read.labels);
    result->regions = std::move(read.regions);
    result->groups = std::move(read.groups);
    return result;
  }();
  return atlas;
}

LoadSettings region_growth(std::vector<std::string> regions, double change) {
  LoadSettings load;
  load.kind = LoadKind::growth;
  load.regions = std::move(regions);
  load.atlas = "aal";
  load.volume_change = change;
  return load;
}

/// The message growth_region_labels throws for `loads`, "" when it throws none.
std::string resolution_error(const std::vector<LoadSettings>& loads) {
  DeformationSettings d;
  d.loads = loads;
  d.region_atlas = aal();
  try {
    growth_region_labels(d);
  } catch (const SettingError& e) {
    return e.key_path() + ": " + e.message();
  }
  return "";
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

} // namespace

// A region by name, a bilateral pair by its name without the side, the cerebral cortex as a
// group: each resolves to its AAL labels (aal.nii.txt: Hippocampus_L 37, _R 38, Amygdala_L 41,
// Caudate_L 71 ... Thalamus_R 78, Precentral_L 1, cerebellum from 91).
TEST(GrowthRegions, NamesAndGroupsResolveToTheAtlasLabels) {
  DeformationSettings d;
  d.region_atlas = aal();
  d.loads = {region_growth({"Hippocampus"}, -0.05), region_growth({"cortex"}, -0.02),
             region_growth({"Amygdala_L", "Thalamus_R"}, 0.01)};
  const auto labels = growth_region_labels(d);
  ASSERT_EQ(labels.size(), 3u);
  EXPECT_EQ(labels[0], (std::vector<std::int32_t>{37, 38}));
  EXPECT_EQ(labels[2], (std::vector<std::int32_t>{41, 78}));
  const std::set<std::int32_t> cortex(labels[1].begin(), labels[1].end());
  EXPECT_EQ(cortex.size(), 90u - 2u - 2u - 8u); // 1-90 but hippocampi, amygdalae, deep nuclei
  for (std::int32_t not_cortex : {37, 38, 41, 42, 71, 74, 78, 91, 116})
    EXPECT_EQ(cortex.count(not_cortex), 0u) << not_cortex;
  for (std::int32_t in_cortex : {1, 2, 39, 40, 89, 90})
    EXPECT_EQ(cortex.count(in_cortex), 1u) << in_cortex;
}

// A misspelt region is refused at its key with the atlas's close names; a region prescribed twice
// (by name and through a group, or in one list) is refused at the second load's key.
TEST(GrowthRegions, AnUnknownOrTwicePrescribedRegionIsRefusedAtItsKey) {
  const std::string unknown = resolution_error({region_growth({"Hipocampus_L"}, -0.05)});
  EXPECT_EQ(unknown.rfind("deformation.loads[0].region: expected a region or group of atlas aal, found "
                          "'Hipocampus_L' (close names: Hippocampus_L",
                          0),
            0u)
      << unknown;
  const std::string twice =
      resolution_error({region_growth({"Hippocampus"}, -0.05), region_growth({"Hippocampus_L"}, -0.02)});
  EXPECT_EQ(twice.rfind("deformation.loads[1].region: expected one growth per region, found a second for "
                        "'Hippocampus_L'",
                        0),
            0u)
      << twice;
  EXPECT_NE(twice.find("the first is deformation.loads[0], given as 'Hippocampus'"), std::string::npos)
      << twice;
  EXPECT_NE(resolution_error({region_growth({"cortex", "Precentral_L"}, -0.02)}).find("'Precentral_L'"),
            std::string::npos);
  EXPECT_EQ(
      resolution_error({region_growth({"Hippocampus_L"}, -0.05), region_growth({"Hippocampus_R"}, -0.05)}),
      "");
}

// The command refuses a misnamed region with the scene line, exit code 2 and nothing written,
// before the anatomy is built.
TEST(GrowthRegions, TheCommandRefusesAMisnamedRegionWithNothingWritten) {
  const fs::path folder = phantasm::testing::fresh_folder("growth-region");
  std::string text = read_text(std::string(PHANTASM_SOURCE_DIR) + "/" + k_scene);
  const std::size_t at = text.find("region: Hippocampus_L");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 21, "region: Hipocampus_L");
  const fs::path scene = folder / "misnamed.yaml";
  std::ofstream(scene) << text;
  const fs::path out = folder / "out";
  const auto result =
      phantasm::testing::run_command({PHANTASM_EXECUTABLE, "run", scene.string(), "-o", out.string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find(scene.string() + ":36:"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("deformation.loads[0].region: expected a region or group of atlas aal, found "
                            "'Hipocampus_L' (close names: Hippocampus_L"),
            std::string::npos)
      << result.err;
  EXPECT_FALSE(fs::exists(out / "derivatives")) << "nothing written";
  fs::remove_all(folder);
}

/// Per grid voxel, the region label of the tet of `body` holding its centre in the rest state
/// (0: none of `labels`): the region as the tets model it.
std::vector<std::int32_t> voxels_of_region_tets(const DeformedBody& body, const RegionAtlas& atlas,
                                                const std::map<std::int32_t, double>& labels,
                                                const ImageGrid& grid) {
  std::vector<std::int32_t> out(static_cast<std::size_t>(grid.voxel_count()), 0);
  for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
    Eigen::Matrix3d edges;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    Eigen::Vector3d low = Eigen::Vector3d::Constant(1e9), high = Eigen::Vector3d::Constant(-1e9);
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d x = body.rest_mm.row(body.tets(t, c)).transpose();
      centroid += 0.25 * x;
      const Eigen::Vector3d index = grid.index_from_world(x);
      low = low.cwiseMin(index);
      high = high.cwiseMax(index);
      if (c > 0) edges.col(c - 1) = x - body.rest_mm.row(body.tets(t, 0)).transpose();
    }
    const std::int32_t label = atlas.label_at(centroid);
    if (labels.count(label) == 0) continue;
    const Eigen::Matrix3d inverse = edges.inverse();
    for (int k = std::max(0, int(std::ceil(low.z()))); k <= std::min(grid.dims.z() - 1, int(high.z())); ++k)
      for (int j = std::max(0, int(std::ceil(low.y()))); j <= std::min(grid.dims.y() - 1, int(high.y())); ++j)
        for (int i = std::max(0, int(std::ceil(low.x()))); i <= std::min(grid.dims.x() - 1, int(high.x()));
             ++i) {
          const Eigen::Vector3d b = inverse * (grid.world_from_index(Eigen::Vector3d(i, j, k)) -
                                               body.rest_mm.row(body.tets(t, 0)).transpose());
          if (b.minCoeff() >= 0.0 && b.sum() <= 1.0) out[voxel_index(grid.dims, i, j, k)] = label;
        }
  }
  return out;
}

// The hippocampus shrinks by 5 %, the amygdala grows by 5 % (tests/data/scenes/growth-region.yaml,
// 5 mm tets, 2 mm grid): each region's tets (centroid in the region) change volume within 1 %
// (absolute) of the prescription, and so does the region's voxels' volume by the mean Jacobian
// of the ground-truth field over them (the AAL region sampled at the reference grid's voxel
// centres). Tissue outside the regions keeps its rest volume up to its elastic answer.
TEST(GrowthRegions, EachRegionsVolumeChangesAsPrescribedOnTheMeshAndInTheJacobian) {
  const Scene scene = phantasm::testing::load_repository_scene(k_scene);
  Reporter quiet = Reporter::silent();
  const Simulation result = simulate(scene, quiet, SimulationStage::voxelization);
  ASSERT_TRUE(result.deformation);
  ASSERT_EQ(result.deformation->bodies.size(), 1u);
  const DeformedBody& body = result.deformation->bodies[0];
  EXPECT_EQ(body.inverted_tets, 0);
  const RegionAtlas& atlas = *aal();
  const std::map<std::int32_t, double> prescribed = {{37, -0.05}, {41, 0.05}};
  std::map<std::int32_t, double> rest, deformed;
  for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int c = 0; c < 4; ++c)
      centroid += 0.25 * body.rest_mm.row(body.tets(t, c)).transpose();
    const std::int32_t label = atlas.label_at(centroid);
    const std::int32_t key = prescribed.count(label) ? label : 0;
    rest[key] += phantasm::testing::body_tet_volume(body.rest_mm, body.tets, t);
    deformed[key] += phantasm::testing::body_tet_volume(body.deformed_mm, body.tets, t);
  }
  ASSERT_TRUE(result.volumes.motion);
  const std::vector<float>& jacobian = result.volumes.motion->jacobian;
  const ImageGrid& grid = result.volumes.grid;
  std::map<std::int32_t, double> jacobian_sum, voxels;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::int32_t label = atlas.label_at(grid.world_from_index(Eigen::Vector3d(i, j, k)));
        if (prescribed.count(label) == 0) continue;
        jacobian_sum[label] += jacobian[voxel_index(grid.dims, i, j, k)];
        voxels[label] += 1.0;
      }
  const std::vector<std::int32_t> meshed = voxels_of_region_tets(body, atlas, prescribed, grid);
  std::map<std::int32_t, double> meshed_sum, meshed_voxels;
  for (std::size_t n = 0; n < meshed.size(); ++n)
    if (meshed[n] != 0) {
      meshed_sum[meshed[n]] += jacobian[n];
      meshed_voxels[meshed[n]] += 1.0;
    }
  for (const auto& [label, change] : prescribed) {
    SCOPED_TRACE("AAL label " + std::to_string(label));
    ASSERT_GT(rest[label], 0.0);
    ASSERT_GT(voxels[label], 50.0);
    ASSERT_GT(meshed_voxels[label], 50.0);
    const double mesh_change = deformed[label] / rest[label] - 1.0;
    const double jacobian_change = jacobian_sum[label] / voxels[label] - 1.0;
    const double meshed_change = meshed_sum[label] / meshed_voxels[label] - 1.0;
    std::printf(
        "AAL %d: prescribed %+.4f, tets %+.4f (%.0f mm^3), Jacobian over its tets' voxels %+.4f (%.0f), "
        "over its atlas voxels %+.4f (%.0f)\n",
        label, change, mesh_change, rest[label], meshed_change, meshed_voxels[label], jacobian_change,
        voxels[label]);
    EXPECT_NEAR(mesh_change, change, 0.01);
    EXPECT_NEAR(meshed_change, change, 0.01);
    EXPECT_GT(mesh_change * change, 0.0) << "the region changes the way prescribed";
  }
  // The hippocampus (7.5 ml, some 500 tets) is many tets across: its atlas voxels, which its
  // tets follow only to a tet's size, change as prescribed too.
  EXPECT_NEAR(jacobian_sum[37] / voxels[37] - 1.0, prescribed.at(37), 0.01);
}
