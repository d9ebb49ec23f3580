// A head from a whole segmentation: `anatomy.segmentation` with a FreeSurfer lookup table or a
// BIDS dseg.tsv, expanded at scene load into nested label_volume organs by the mapping.

#include "core/error.hpp"
#include "io/nifti_file.hpp"
#include "io/shape_files.hpp"
#include "scene/scene.hpp"
#include "tests/support/aseg_fixture.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <set>
#include <sstream>

using namespace phantasm;
using phantasm::testing::k_lut;
using phantasm::testing::write_aseg_fixture;
using phantasm::testing::write_text_file;
namespace fs = std::filesystem;

namespace {

std::string scene_text(const std::string& segmentation, const std::string& organs = "") {
  return "phantasm: 1\nname: segmentation\nseed: 1\nfield_strength_T: 3.0\n"
         "grid: {field_of_view_mm: 96, voxel_size_mm: 2}\n"
         "anatomy:\n  base_mesh_triangles: 80\n  segmentation: " +
         segmentation + "\n" + organs;
}

SceneLoadResult load(const fs::path& folder, const std::string& text) {
  write_text_file(folder / "scene.yaml", text);
  return load_scene(folder / "scene.yaml");
}

/// Each organ as "name < container: tissue [labels]".
std::vector<std::string> organ_lines(const Scene& scene) {
  std::vector<std::string> lines;
  for (const OrganSettings& organ : scene.anatomy.organs) {
    std::string line =
        organ.name + " < " + organ.inside + ": " + organ.tissue + (organ.solid ? " solid" : "") + " [";
    for (const std::string& label : organ.shape.labels)
      line += (line.back() == '[' ? "" : " ") + label;
    lines.push_back(line + "]");
  }
  return lines;
}

const std::vector<std::string> k_expected_organs = {
    "csf < : csf solid [24]",
    "grey_matter < csf: gray_matter [3 42]",
    "white_matter < grey_matter: white_matter [2 41]",
    "brainstem < csf: white_matter [16]",
    "left_lateral_ventricle < white_matter: csf [4]",
    "left_thalamus < white_matter: gray_matter [10]",
    "left_hippocampus < grey_matter: gray_matter [17]",
    "right_lateral_ventricle < white_matter: csf [43]",
    "right_thalamus < white_matter: gray_matter [49]",
    "right_hippocampus < grey_matter: gray_matter [53]",
};

/// The diagnostics of a scene that must not load.
std::string refusal(const fs::path& folder, const std::string& text) {
  const SceneLoadResult result = load(folder, text);
  EXPECT_FALSE(result.scene) << "the scene loaded";
  return format_diagnostics(result.problems);
}

} // namespace

TEST(Segmentation, AnAsegWithItsLookupTableBecomesTheNestedOrgansOfTheFreeSurferMapping) {
  const fs::path folder = write_aseg_fixture("segmentation-lut");
  const SceneLoadResult result =
      load(folder, scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer}"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  EXPECT_EQ(organ_lines(*result.scene), k_expected_organs);
  for (const OrganSettings& organ : result.scene->anatomy.organs) {
    EXPECT_EQ(organ.shape.kind, ShapeKind::label_volume);
    EXPECT_EQ(organ.shape.file, folder / "aseg.nii.gz");
    EXPECT_EQ(organ.shape.smoothing_mm, 1.0);
  }
  // Read as label_volume organs: each container's surface bounds its labels and those nested in
  // it, so the CSF holds every label of the volume and the cortex the whole cerebrum.
  const std::map<std::string, ShapeData> files = read_shape_files(result.scene->anatomy);
  EXPECT_EQ(files.at("csf").target_labels,
            (std::vector<std::int32_t>{2, 3, 4, 10, 16, 17, 24, 41, 42, 43, 49, 53}));
  EXPECT_EQ(files.at("grey_matter").target_labels,
            (std::vector<std::int32_t>{2, 3, 4, 10, 17, 41, 42, 43, 49, 53}));
  EXPECT_EQ(files.at("white_matter").target_labels, (std::vector<std::int32_t>{2, 4, 10, 41, 43, 49}));
  EXPECT_EQ(files.at("left_thalamus").target_labels, (std::vector<std::int32_t>{10}));
}

TEST(Segmentation, ADsegTsvGivesTheSameOrgansAndScenesMayAddOrgansOfTheirOwn) {
  const fs::path folder = write_aseg_fixture("segmentation-tsv");
  const SceneLoadResult result = load(
      folder, scene_text("{file: aseg.nii.gz, table: aseg_dseg.tsv, mapping: freesurfer, smoothing_mm: 2}",
                         "  organs:\n    - {name: lesion, tissue: csf, inside: left_thalamus, solid: false, "
                         "shape: {type: ellipsoid, center_mm: [-9, -8, 4], radii_mm: 1}}\n"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  std::vector<std::string> lines = organ_lines(*result.scene);
  ASSERT_EQ(lines.size(), k_expected_organs.size() + 1);
  EXPECT_EQ(lines.front(), "lesion < left_thalamus: csf []"); // the scene's own organ keeps index 0
  lines.erase(lines.begin());
  EXPECT_EQ(lines, k_expected_organs);
  EXPECT_EQ(result.scene->anatomy.organs.back().shape.smoothing_mm, 2.0);
  EXPECT_EQ(result.scene->organs.size(), k_expected_organs.size() + 1);
}

TEST(Segmentation, AMappingOfItsOwnNamesItsOrgansTissuesAndNesting) {
  const fs::path folder = write_aseg_fixture("segmentation-custom");
  const SceneLoadResult result = load(folder, scene_text(R"(
    file: aseg.nii.gz
    table: aseg_dseg.tsv
    mapping:
      - {organ: head, tissue: csf, solid: true, labels: [CSF, Brain-Stem]}
      - {organ: brain, tissue: gray_matter, inside: head, labels: [Left-Cerebral-Cortex, Right-Cerebral-Cortex, Left-Hippocampus, Right-Hippocampus]}
      - {organ: deep, tissue: white_matter, inside: brain, labels: [Left-Cerebral-White-Matter, Right-Cerebral-White-Matter, Left-Thalamus, Right-Thalamus]}
      - {organ: unused, tissue: csf, inside: deep, labels: [Left-Caudate]}
      - {organ: ventricles, tissue: csf, inside: unused, labels: [Left-Lateral-Ventricle, Right-Lateral-Ventricle]})"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  // "unused" has no voxels: it is left out and the ventricles nest in its container.
  EXPECT_EQ(organ_lines(*result.scene), (std::vector<std::string>{
                                            "head < : csf solid [16 24]",
                                            "brain < head: gray_matter [3 17 42 53]",
                                            "deep < brain: white_matter [2 10 41 49]",
                                            "ventricles < deep: csf [4 43]",
                                        }));
  // Later messages about an organ (its shape, its tissue) point at the mapping entry that made it.
  EXPECT_EQ(result.scene->location_of("anatomy.organs[3].shape.label").line, 16);
  EXPECT_EQ(result.scene->location_of("anatomy.organs[0].tissue").line, 12);
}

TEST(Segmentation, AVolumeLabelMissingFromItsTableIsNamedWithBothFiles) {
  const fs::path folder =
      write_aseg_fixture("segmentation-missing", 77); // WM-hypointensities: not in the excerpt
  for (const char* table : {"FreeSurferColorLUT.txt", "aseg_dseg.tsv"}) {
    const std::string problems = refusal(
        folder, scene_text(std::string("{file: aseg.nii.gz, table: ") + table + ", mapping: freesurfer}"));
    EXPECT_NE(problems.find("scene.yaml:8:"), std::string::npos) << problems;
    EXPECT_NE(problems.find("anatomy.segmentation.table: " + (folder / "aseg.nii.gz").string() +
                            ": label 77 has voxels but no line in " + (folder / table).string()),
              std::string::npos)
        << problems;
  }
}

TEST(Segmentation, ALabelTheMappingDoesNotListIsNamedWithItsTableName) {
  const fs::path folder = write_aseg_fixture("segmentation-unmapped");
  const std::string problems =
      refusal(folder, scene_text(R"({file: aseg.nii.gz, table: aseg_dseg.tsv, mapping: [
      {organ: brain, tissue: gray_matter, labels: [CSF, Brain-Stem, Left-Cerebral-Cortex, Right-Cerebral-Cortex]}]})"));
  EXPECT_NE(problems.find("anatomy.segmentation.mapping: " + (folder / "aseg.nii.gz").string() +
                          ": label 2 ('Left-Cerebral-White-Matter') has voxels but no organ in the mapping"),
            std::string::npos)
      << problems;
}

TEST(Segmentation, TableLinesThatDoNotParseAreNamedByFileAndLine) {
  const fs::path folder = write_aseg_fixture("segmentation-bad-table");
  std::string lut = k_lut;
  lut.replace(lut.find("17  Left-Hippocampus"), 19, "17  Left Hippocampus");
  write_text_file(folder / "bad-lut.txt", lut);
  std::string problems =
      refusal(folder, scene_text("{file: aseg.nii.gz, table: bad-lut.txt, mapping: freesurfer}"));
  EXPECT_NE(problems.find((folder / "bad-lut.txt").string() +
                          ":11: expected 'index name R G B A' (a FreeSurfer lookup table line), found '17  "
                          "Left Hippocampus"),
            std::string::npos)
      << problems;

  write_text_file(folder / "bad_dseg.tsv", "index\tname\n3\tLeft-Cerebral-Cortex\nx3\tcortex\n");
  problems = refusal(folder, scene_text("{file: aseg.nii.gz, table: bad_dseg.tsv, mapping: freesurfer}"));
  EXPECT_NE(problems.find((folder / "bad_dseg.tsv").string() +
                          ":3: expected a label in [0, 65535] under index and a name under name, found "
                          "'x3\tcortex'"),
            std::string::npos)
      << problems;

  write_text_file(folder / "no_header.tsv", "3\tLeft-Cerebral-Cortex\n");
  problems = refusal(folder, scene_text("{file: aseg.nii.gz, table: no_header.tsv, mapping: freesurfer}"));
  EXPECT_NE(problems.find((folder / "no_header.tsv").string() + ":1: expected a header"), std::string::npos)
      << problems;

  write_text_file(folder / "twice_dseg.tsv", "index\tname\n3\tLeft-Cerebral-Cortex\n3\tcortex\n");
  problems = refusal(folder, scene_text("{file: aseg.nii.gz, table: twice_dseg.tsv, mapping: freesurfer}"));
  EXPECT_NE(problems.find(":3: expected each label once, found label 3 again"), std::string::npos)
      << problems;
}

TEST(Segmentation, AnUnknownMappingOrMissingFilesAreSceneErrorsAtTheirKeys) {
  const fs::path folder = write_aseg_fixture("segmentation-keys");
  std::string problems =
      refusal(folder, scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: synthseg}"));
  EXPECT_NE(problems.find("scene.yaml:8:"), std::string::npos) << problems;
  EXPECT_NE(problems.find("anatomy.segmentation.mapping: expected freesurfer or a list of organs with the "
                          "table's names of their labels, found 'synthseg'"),
            std::string::npos)
      << problems;
  problems =
      refusal(folder, scene_text("{file: gone.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer}"));
  EXPECT_NE(problems.find("anatomy.segmentation.file: expected an existing file, found no file"),
            std::string::npos)
      << problems;
  problems = refusal(folder, scene_text("{file: aseg.nii.gz, mapping: freesurfer, labels: 3}"));
  EXPECT_NE(problems.find("anatomy.segmentation.table: expected"), std::string::npos) << problems;
  EXPECT_NE(problems.find("labels"), std::string::npos) << problems; // the unknown key
}

TEST(Segmentation, ANameInTwoOrgansOrAVolumeWithoutLabelsIsRefused) {
  const fs::path folder = write_aseg_fixture("segmentation-twice");
  std::string problems = refusal(folder, scene_text(R"({file: aseg.nii.gz, table: aseg_dseg.tsv, mapping: [
      {organ: a, tissue: csf, labels: [CSF, Brain-Stem]},
      {organ: b, tissue: csf, labels: [Left-Thalamus, Brain-Stem]}]})"));
  EXPECT_NE(problems.find("anatomy.segmentation.mapping[1].labels: expected each name in one organ, found "
                          "'Brain-Stem' in organ b and in organ a"),
            std::string::npos)
      << problems;

  ImageGrid grid;
  grid.dims = {8, 8, 8};
  write_nifti_labels(folder / "empty.nii.gz", grid, std::vector<std::int32_t>(512, 0));
  problems = refusal(folder, scene_text("{file: empty.nii.gz, table: aseg_dseg.tsv, mapping: freesurfer}"));
  EXPECT_NE(problems.find("anatomy.segmentation.file: " + (folder / "empty.nii.gz").string() +
                          ": expected labels (voxels other than 0), found none"),
            std::string::npos)
      << problems;
}

TEST(Segmentation, EveryLabelOfAReconAllAsegGetsAnOrganOfTheFreeSurferMapping) {
  // The labels recon-all writes to aseg.mgz (and SynthSeg a subset of), one voxel each.
  const std::vector<std::pair<int, std::string>> aseg = {{2, "Left-Cerebral-White-Matter"},
                                                         {3, "Left-Cerebral-Cortex"},
                                                         {4, "Left-Lateral-Ventricle"},
                                                         {5, "Left-Inf-Lat-Vent"},
                                                         {7, "Left-Cerebellum-White-Matter"},
                                                         {8, "Left-Cerebellum-Cortex"},
                                                         {10, "Left-Thalamus"},
                                                         {11, "Left-Caudate"},
                                                         {12, "Left-Putamen"},
                                                         {13, "Left-Pallidum"},
                                                         {14, "3rd-Ventricle"},
                                                         {15, "4th-Ventricle"},
                                                         {16, "Brain-Stem"},
                                                         {17, "Left-Hippocampus"},
                                                         {18, "Left-Amygdala"},
                                                         {24, "CSF"},
                                                         {26, "Left-Accumbens-area"},
                                                         {28, "Left-VentralDC"},
                                                         {30, "Left-vessel"},
                                                         {31, "Left-choroid-plexus"},
                                                         {41, "Right-Cerebral-White-Matter"},
                                                         {42, "Right-Cerebral-Cortex"},
                                                         {43, "Right-Lateral-Ventricle"},
                                                         {44, "Right-Inf-Lat-Vent"},
                                                         {46, "Right-Cerebellum-White-Matter"},
                                                         {47, "Right-Cerebellum-Cortex"},
                                                         {49, "Right-Thalamus"},
                                                         {50, "Right-Caudate"},
                                                         {51, "Right-Putamen"},
                                                         {52, "Right-Pallidum"},
                                                         {53, "Right-Hippocampus"},
                                                         {54, "Right-Amygdala"},
                                                         {58, "Right-Accumbens-area"},
                                                         {60, "Right-VentralDC"},
                                                         {62, "Right-vessel"},
                                                         {63, "Right-choroid-plexus"},
                                                         {72, "5th-Ventricle"},
                                                         {77, "WM-hypointensities"},
                                                         {78, "Left-WM-hypointensities"},
                                                         {79, "Right-WM-hypointensities"},
                                                         {80, "non-WM-hypointensities"},
                                                         {81, "Left-non-WM-hypointensities"},
                                                         {82, "Right-non-WM-hypointensities"},
                                                         {85, "Optic-Chiasm"},
                                                         {251, "CC_Posterior"},
                                                         {252, "CC_Mid_Posterior"},
                                                         {253, "CC_Central"},
                                                         {254, "CC_Mid_Anterior"},
                                                         {255, "CC_Anterior"}};
  const fs::path folder = write_aseg_fixture("segmentation-recon-all");
  ImageGrid grid;
  grid.dims = {12, 12, 12};
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  std::string lut = "0 Unknown 0 0 0 0\n";
  for (std::size_t n = 0; n < aseg.size(); ++n) {
    labels[voxel_index(grid.dims, 2 + static_cast<int>(n % 8), 2 + static_cast<int>(n / 8), 5)] =
        aseg[n].first;
    lut += std::to_string(aseg[n].first) + " " + aseg[n].second + " 1 2 3 0\n";
  }
  write_nifti_labels(folder / "recon-all.nii.gz", grid, labels);
  write_text_file(folder / "recon-all-lut.txt", lut);
  const SceneLoadResult result =
      load(folder, scene_text("{file: recon-all.nii.gz, table: recon-all-lut.txt, mapping: freesurfer}"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  std::multiset<std::string> mapped;
  for (const OrganSettings& organ : result.scene->anatomy.organs)
    mapped.insert(organ.shape.labels.begin(), organ.shape.labels.end());
  std::multiset<std::string> expected;
  for (const auto& [value, name] : aseg)
    expected.insert(std::to_string(value));
  EXPECT_EQ(mapped, expected); // each label in exactly one organ
  EXPECT_EQ(result.scene->anatomy.organs.size(), 26u);
  EXPECT_EQ(result.scene->find_organ("right_cerebellum_white_matter")->inside, "right_cerebellum");
  EXPECT_EQ(result.scene->find_organ("left_cerebellum")->inside, "csf");
}

TEST(Segmentation, NamePatternsTakeEveryNameOfTheTableTheyMatch) {
  const fs::path folder = write_aseg_fixture("segmentation-patterns");
  const SceneLoadResult result = load(folder, scene_text(R"(
    file: aseg.nii.gz
    table: aseg_dseg.tsv
    mapping:
      - {organ: head, tissue: csf, material: soft, solid: true, labels: [CSF, Brain-Stem]}
      - {organ: left, tissue: gray_matter, material: soft, inside: head, labels: ["Left-*"]}
      - {organ: right, tissue: gray_matter, inside: head, labels: ["Right-Cerebral-*", "Right-Thalamu?", "Right-*"]})",
                                                         "materials:\n  soft: {youngs_modulus_Pa: 3000, "
                                                         "poisson_ratio: 0.45, density_kg_m3: 1040}\n"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  // Left-Caudate is in the table but has no voxels; a name matched twice within one organ
  // (Right-Thalamus, by Right-Thalamu? and Right-*) is no conflict.
  EXPECT_EQ(organ_lines(*result.scene), (std::vector<std::string>{
                                            "head < : csf solid [16 24]",
                                            "left < head: gray_matter [2 3 4 10 17]",
                                            "right < head: gray_matter [41 42 43 49 53]",
                                        }));
  EXPECT_EQ(result.scene->anatomy.organs[1].material, "soft");
  EXPECT_EQ(result.scene->anatomy.organs[2].material, "");
}

TEST(Segmentation, APatternMatchingNoNameOrANameTwoPatternsGiveTwoOrgansIsRefused) {
  const fs::path folder = write_aseg_fixture("segmentation-bad-patterns");
  std::string problems = refusal(folder, scene_text(R"({file: aseg.nii.gz, table: aseg_dseg.tsv, mapping: [
      {organ: a, tissue: csf, labels: ["*"]},
      {organ: b, tissue: csf, labels: ["Middle-*"]}]})"));
  EXPECT_NE(problems.find("anatomy.segmentation.mapping[1].labels: expected a name of " +
                          (folder / "aseg_dseg.tsv").string() +
                          " matching the pattern 'Middle-*' (organ b), found none"),
            std::string::npos)
      << problems;
  problems = refusal(folder, scene_text(R"({file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: [
      {organ: a, tissue: csf, labels: [CSF, Brain-Stem, "*-Cerebral-*"]},
      {organ: b, tissue: csf, labels: ["*-Thalamus", "Left-*"]}]})"));
  EXPECT_NE(problems.find("scene.yaml:10:"), std::string::npos) << problems;
  EXPECT_NE(problems.find("anatomy.segmentation.mapping[1].labels: expected each name in one organ, found "
                          "'Left-Cerebral-White-Matter' in organ b and in organ a"),
            std::string::npos)
      << problems;
  // A pattern's mistake is a scene error, not a label without an organ further on.
  EXPECT_EQ(problems.find("has voxels but no organ"), std::string::npos) << problems;
}

namespace {

const fs::path k_templates = "/usr/share/mricron/templates";

/// A dseg.tsv whose first two columns are index and name: label -> name.
std::map<std::int32_t, std::string> read_index_names(const fs::path& file) {
  std::map<std::int32_t, std::string> table;
  std::istringstream in(phantasm::testing::read_file(file));
  std::string line;
  std::getline(in, line); // the header
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::int32_t index = 0;
    std::string name;
    if (fields >> index >> name) table.emplace(index, name);
  }
  return table;
}
const fs::path k_macaque_table =
    fs::path(PHANTASM_SOURCE_DIR) / "data-synthetic" / "macaque" / "inia19-NeuroMaps_dseg.tsv";

} // namespace

// The NeuroMaps labels come without names: the shipped table is derived from the mricron-data
// files by scripts/inia19_table.py, and deriving it again gives the same file, byte for byte.
TEST(Segmentation, TheShippedMacaqueTableIsTheOneItsScriptDerives) {
  if (!fs::exists(k_templates / "inia19-NeuroMaps.nii.gz")) GTEST_SKIP() << "mricron-data is not installed";
  const fs::path folder = phantasm::testing::fresh_folder("segmentation-inia19-table");
  const auto run = phantasm::testing::run_command(
      {PHANTASM_PYTHON, (fs::path(PHANTASM_SOURCE_DIR) / "scripts" / "inia19_table.py").string(),
       (folder / "derived_dseg.tsv").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("Otsu thresholds 74 and 99; 724 labels"), std::string::npos) << run.err;
  const std::string derived = phantasm::testing::read_file(folder / "derived_dseg.tsv");
  EXPECT_EQ(derived, phantasm::testing::read_file(k_macaque_table))
      << "data-synthetic/macaque/inia19-NeuroMaps_dseg.tsv is stale: run scripts/inia19_table.py";
  // Its names: side by number (n left, 1000 + n right), class by intensity, n again.
  const auto table = read_index_names(folder / "derived_dseg.tsv");
  EXPECT_EQ(table.size(), 724u);
  for (const auto& [label, name] : table) {
    const std::string side = label < 1000 ? "left_" : "right_";
    char number[8];
    std::snprintf(number, sizeof number, "_%04d", label % 1000);
    EXPECT_EQ(name.rfind(side, 0), 0u) << label << " " << name;
    EXPECT_EQ(name.substr(name.size() - 5), number) << label << " " << name;
    const std::string kind = name.substr(side.size(), name.size() - side.size() - 5);
    EXPECT_TRUE(kind == "grey" || kind == "white") << label << " " << name;
  }
}

// The shipped macaque scene's two organs take every NeuroMaps label by the table's patterns:
// the brain the grey ones, the white matter nested in it the white ones.
TEST(Segmentation, TheMacaqueSceneMakesABrainHoldingItsWhiteMatterFromEveryLabel) {
  if (!fs::exists(k_templates / "inia19-NeuroMaps.nii.gz")) GTEST_SKIP() << "mricron-data is not installed";
  const SceneLoadResult result =
      load_scene(fs::path(PHANTASM_SOURCE_DIR) / "data-synthetic" / "macaque-brain.yaml");
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  const auto table = read_index_names(k_macaque_table);
  std::size_t grey = 0;
  for (const auto& [label, name] : table)
    grey += name.find("_grey_") != std::string::npos;
  const auto& organs = result.scene->anatomy.organs;
  ASSERT_EQ(organs.size(), 2u);
  EXPECT_EQ(organs[0].name, "brain");
  EXPECT_TRUE(organs[0].solid);
  EXPECT_EQ(organs[0].material, "brain");
  EXPECT_EQ(organs[0].shape.labels.size(), grey);
  EXPECT_EQ(organs[1].name, "white_matter");
  EXPECT_EQ(organs[1].inside, "brain");
  EXPECT_EQ(organs[1].shape.labels.size(), table.size() - grey);
  for (const std::string& label : organs[1].shape.labels)
    EXPECT_NE(table.at(std::stoi(label)).find("_white_"), std::string::npos) << label;
}

namespace {

/// A T1 image on a 2 mm grid of `voxels`^3 voxels centred on the origin (the aseg fixture's grid
/// at 48): a bright head of radius 46 mm around the brain.
void write_t1(const fs::path& path, int voxels) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i::Constant(voxels);
  grid.world_from_voxel.topLeftCorner<3, 3>() *= 2.0;
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-(voxels - 1.0));
  std::vector<float> values(static_cast<std::size_t>(grid.voxel_count()), 0.0f);
  std::size_t n = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i, ++n)
        values[n] = grid.world_from_index(Eigen::Vector3d(i, j, k)).norm() < 46.0 ? 120.0f : 0.0f;
  write_nifti(path, grid, values);
}

} // namespace

// With a T1 the segmentation's organs come from its head (an atlas named after both files): the
// scalp and the skull first, the mapping's outermost organ (csf) in the skull with the outer CSF.
TEST(Segmentation, AT1AddsTheScalpAndTheSkullAroundTheMappingsOrgans) {
  const fs::path folder = write_aseg_fixture("segmentation-t1");
  write_t1(folder / "t1.nii.gz", 48);
  const SceneLoadResult result = load(
      folder,
      scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer, t1: t1.nii.gz}"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  std::vector<std::string> expected = {"scalp < : skin [scalp subcutaneous_fat muscle]",
                                       "skull < scalp: bone_cortical [skull bone_marrow]",
                                       "csf < skull: csf solid [24 outer_csf]"};
  expected.insert(expected.end(), k_expected_organs.begin() + 1, k_expected_organs.end());
  EXPECT_EQ(organ_lines(*result.scene), expected);
  for (const OrganSettings& organ : result.scene->anatomy.organs)
    EXPECT_EQ(organ.shape.atlas,
              "segmentation:" + (folder / "aseg.nii.gz").string() + "|t1:" + (folder / "t1.nii.gz").string())
        << organ.name;
}

TEST(Segmentation, AMissingT1OrOneThatDoesNotCoverTheLabelsIsRefusedAtItsKey) {
  const fs::path folder = write_aseg_fixture("segmentation-t1-bad");
  std::string problems = refusal(
      folder,
      scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer, t1: gone.nii}"));
  EXPECT_NE(problems.find("scene.yaml:8:"), std::string::npos) << problems;
  EXPECT_NE(problems.find("anatomy.segmentation.t1: expected an existing T1 image (NIfTI) of the "
                          "segmentation's subject, found no file at '" +
                          (folder / "gone.nii").string() + "'"),
            std::string::npos)
      << problems;
  // 30^3 voxels of 2 mm: x -29..29 mm, where the aseg's CSF reaches +-41 mm.
  write_t1(folder / "small.nii.gz", 30);
  problems = refusal(
      folder,
      scene_text(
          "{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer, t1: small.nii.gz}"));
  EXPECT_NE(problems.find("scene.yaml:8:"), std::string::npos) << problems;
  EXPECT_NE(problems.find("anatomy.segmentation.t1: " + (folder / "small.nii.gz").string() +
                          ": expected a T1 whose grid covers the labelled voxels of " +
                          (folder / "aseg.nii.gz").string()),
            std::string::npos)
      << problems;
  // The organs t1 adds keep their names.
  write_t1(folder / "t1.nii.gz", 48);
  problems = refusal(folder, scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, t1: t1.nii.gz, "
                                        "mapping: [{organ: skull, tissue: csf, labels: ['*']}]}"));
  EXPECT_NE(
      problems.find("anatomy.segmentation.mapping[0].organ: expected an organ name other than scalp and "
                    "skull, which t1 adds, found 'skull'"),
      std::string::npos)
      << problems;
  // A file that is no NIfTI is named too.
  write_text_file(folder / "text.nii", "not an image");
  problems = refusal(
      folder,
      scene_text("{file: aseg.nii.gz, table: FreeSurferColorLUT.txt, mapping: freesurfer, t1: text.nii}"));
  EXPECT_NE(problems.find("anatomy.segmentation.t1: "), std::string::npos) << problems;
  EXPECT_NE(problems.find("text.nii"), std::string::npos) << problems;
}
