#include "anatomy/shape_source.hpp"
#include "scene/scene.hpp"
#include "scene/scene_json.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

using namespace phantasm;

namespace {

const std::string k_minimal = R"(phantasm: 1
name: ball
seed: 7
field_strength_T: 3.0
grid:
  field_of_view_mm: 64
  voxel_size_mm: [2, 2, 4]
anatomy:
  organs:
    - name: ball
      tissue: white_matter
      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}
)";

SceneLoadResult parse(const std::string& text) {
  return parse_scene(text, "scene.yaml");
}

/// The only problem of a scene, formatted; fails the test when there is not exactly one.
std::string only_problem(const std::string& text) {
  const SceneLoadResult result = parse(text);
  EXPECT_FALSE(result.scene.has_value());
  EXPECT_EQ(result.problems.size(), 1u) << format_diagnostics(result.problems);
  return result.problems.empty() ? "" : result.problems.front().format();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

} // namespace

TEST(ParseScene, MinimalSceneGetsDocumentedDefaults) {
  const SceneLoadResult result = parse(k_minimal);
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  const Scene& s = *result.scene;
  EXPECT_EQ(s.name, "ball");
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.grid.field_of_view_mm, Eigen::Vector3d(64, 64, 64));
  EXPECT_EQ(s.grid.grid().dims, Eigen::Vector3i(32, 32, 16));
  EXPECT_EQ(s.grid.orientation, "RAS");
  EXPECT_EQ(s.anatomy.organs.at(0).shape.radii_mm, Eigen::Vector3d(20, 20, 20));
  EXPECT_EQ(s.deformation.mode, DeformationMode::none);
  EXPECT_EQ(s.outputs.subject, "01");
  EXPECT_TRUE(s.mri.sequences.empty());
  EXPECT_EQ(s.sha256.size(), 64u);
}

TEST(ParseScene, KeyLocationsAreRememberedForLaterMessages) {
  const Scene s = *parse(k_minimal).scene;
  const SourceLocation voxel = s.location_of("grid.voxel_size_mm");
  EXPECT_EQ(voxel.line, 7);
  EXPECT_EQ(voxel.column, 18);
  // An unknown path falls back to its nearest known ancestor.
  EXPECT_EQ(s.location_of("grid.voxel_size_mm[5]").line, 7);
}

TEST(ParseScene, UnknownKeyListsTheKeysThatWouldBeAccepted) {
  const std::string message =
      only_problem(replaced(k_minimal, "  voxel_size_mm", "  voxelsize_mm: 1\n  voxel_size_mm"));
  EXPECT_EQ(message,
            "scene.yaml:7:3: grid.voxelsize_mm: expected one of the keys center_mm, field_of_view_mm, "
            "orientation, voxel_size_mm, found unknown key 'voxelsize_mm' (did you mean 'voxel_size_mm'?)");
}

TEST(ParseScene, WrongTypesSayWhatWasExpectedAndFound) {
  EXPECT_EQ(only_problem(replaced(k_minimal, "seed: 7", "seed: many")),
            "scene.yaml:3:7: seed: expected an integer in [0, 9223372036854775807], found 'many'");
  EXPECT_EQ(
      only_problem(replaced(k_minimal, "field_strength_T: 3.0", "field_strength_T: [3]")),
      "scene.yaml:4:19: field_strength_T: expected a number in T in (0, 11.7], found a list of 1 items");
  // A quoted number is text, not a number.
  EXPECT_NE(only_problem(replaced(k_minimal, "seed: 7", "seed: \"7\"")).find("found '7'"), std::string::npos);
}

TEST(ParseScene, OutOfRangeValuesPointAtTheElement) {
  EXPECT_EQ(only_problem(replaced(k_minimal, "[2, 2, 4]", "[2, -2, 4]")),
            "scene.yaml:7:22: grid.voxel_size_mm[1]: expected a number in mm greater than 0, found '-2'");
}

TEST(ParseScene, TetMeshSettingsWithoutATetSizeAreRefusedAndWithOneRead) {
  EXPECT_EQ(only_problem(replaced(k_minimal, "anatomy:\n", "anatomy:\n  tet_interfaces: materials\n")),
            "scene.yaml:9:19: anatomy.tet_interfaces: expected anatomy.tet_size_mm beside it (it shapes the "
            "tet meshes of that size), found no anatomy.tet_size_mm");
  const SceneLoadResult result = parse(
      replaced(k_minimal, "anatomy:\n",
               "anatomy:\n  tet_size_mm: 5\n  tet_facet_distance_mm: 1.5\n  tet_interfaces: materials\n"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  EXPECT_EQ(result.scene->anatomy.tet_facet_distance_mm, 1.5);
  EXPECT_EQ(result.scene->anatomy.tet_interfaces, TetInterfaces::materials);
}

TEST(ParseScene, MissingRequiredKeyIsReportedAtItsParent) {
  const std::string message = only_problem(replaced(k_minimal, "      tissue: white_matter\n", ""));
  EXPECT_NE(
      message.find("scene.yaml:10:7: anatomy.organs[0].tissue: expected a non-empty text, found no such key"),
      std::string::npos)
      << message;
}

TEST(ParseScene, EveryProblemIsReportedNotOnlyTheFirst) {
  std::string text = replaced(k_minimal, "seed: 7", "seed: -1");
  text = replaced(text, "[2, 2, 4]", "[2, 2, 0]");
  const SceneLoadResult result = parse(text);
  EXPECT_EQ(result.problems.size(), 2u) << format_diagnostics(result.problems);
}

TEST(ParseScene, SyntaxErrorsGiveTheirLineAndColumn) {
  const SceneLoadResult result = parse("phantasm: 1\ngrid: [1, 2\nname: x\n");
  ASSERT_EQ(result.problems.size(), 1u);
  EXPECT_GT(result.problems[0].where.line, 1);
  EXPECT_NE(result.problems[0].message.find("expected valid YAML"), std::string::npos);
}

TEST(ParseScene, DuplicateKeysAreRejected) {
  const std::string message = only_problem(replaced(k_minimal, "seed: 7\n", "seed: 7\nseed: 8\n"));
  EXPECT_NE(message.find("scene.yaml:4:1: seed: expected each key once"), std::string::npos) << message;
}

TEST(ParseScene, TissuesMustExistInTheTableOrTheScene) {
  const std::string message = only_problem(replaced(k_minimal, "tissue: white_matter", "tissue: brain"));
  EXPECT_NE(
      message.find("scene.yaml:11:15: anatomy.organs[0].tissue: expected a tissue of the built-in table"),
      std::string::npos)
      << message;
  const std::string custom = replaced(k_minimal, "tissue: white_matter", "tissue: gel") +
                             "tissues:\n  gel: {T1_ms: 1000, T2_ms: 100, T2star_ms: 50, PD: 1}\n";
  EXPECT_TRUE(parse(custom).scene.has_value());
}

TEST(ParseScene, SequencesNeedTheTissueValuesTheirSignalEquationReads) {
  const std::string csf = replaced(k_minimal, "tissue: white_matter", "tissue: csf");
  const std::string gre =
      "sequences:\n  - {name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 4, flip_deg: 20}\n";
  const std::string message = only_problem(csf + gre);
  EXPECT_NE(message.find("sequences[0].type: this sequence needs T2star_ms of tissue 'csf' at 3 T"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("expected tissues.csf.T2star_ms"), std::string::npos);
  // A spin echo reads T2, not T2*, and the table has T2 of CSF.
  EXPECT_TRUE(parse(csf + "sequences:\n  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 100}\n").scene);
  // A scene value completes the table.
  EXPECT_TRUE(parse(csf + gre + "tissues:\n  csf: {T2star_ms: 100}\n").scene);
}

TEST(ParseScene, SequenceTimingsAreCheckedAgainstEachOther) {
  const auto problem_of = [&](const std::string& sequence) {
    return only_problem(k_minimal + "sequences:\n  - " + sequence + "\n");
  };
  EXPECT_NE(problem_of("{name: T2w, type: spin_echo, TR_ms: 40, TE_ms: 40}")
                .find("TE_ms: expected TE_ms less than TR_ms (40), found 40"),
            std::string::npos);
  EXPECT_NE(
      problem_of(
          "{name: FLAIR, type: inversion_recovery, readout: spin_echo, TR_ms: 1000, TI_ms: 950, TE_ms: 80}")
          .find("TI_ms: expected TI_ms + TE_ms less than TR_ms"),
      std::string::npos);
  EXPECT_NE(problem_of("{name: bSSFP, type: bssfp, TR_ms: 5, TE_ms: 2, flip_deg: 50}")
                .find("TE_ms = TR_ms / 2 = 2.5"),
            std::string::npos);
  EXPECT_NE(
      problem_of(
          "{name: T1w, type: mprage, TR_ms: 2300, TI_ms: 500, TE_ms: 3, flip_deg: 9, echo_spacing_ms: 7, "
          "turbo_factor: 176}")
          .find("TI_ms: expected TI_ms greater than half the echo train (616 ms)"),
      std::string::npos);
  EXPECT_NE(problem_of("{name: T1w, type: spoiled_gre, TR_ms: 20, TE_ms: 4, flip_deg: 190}")
                .find("flip_deg: expected a number in degrees in [0, 180]"),
            std::string::npos);
  // Keys of other sequence types are unknown here.
  EXPECT_NE(problem_of("{name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 100, TI_ms: 3}")
                .find("found unknown key 'TI_ms'"),
            std::string::npos);
}

TEST(ParseScene, InversionRecoveryReadoutIsOneOfTheDeclaredReadouts) {
  const std::string ir = "{name: FLAIR, type: inversion_recovery, TR_ms: 9000, TI_ms: 2500, TE_ms: 80";
  const auto scene_of = [&](const std::string& readout) {
    return k_minimal + "sequences:\n  - " + ir + readout + "}\n";
  };
  const Scene spin = *parse(scene_of(", readout: spin_echo")).scene;
  EXPECT_EQ(spin.mri.sequences.at(0).readout, Readout::spin_echo);
  const Scene gradient = *parse(scene_of(", readout: gradient_echo")).scene;
  EXPECT_EQ(gradient.mri.sequences.at(0).readout, Readout::gradient_echo);
  const std::string wrong = only_problem(scene_of(", readout: echo_planar"));
  EXPECT_NE(wrong.find("sequences[0].readout: expected one of gradient_echo, spin_echo, found 'echo_planar'"),
            std::string::npos)
      << wrong;
  // The inversion-recovery type requires it.
  const std::string missing = only_problem(scene_of(""));
  EXPECT_NE(missing.find("readout"), std::string::npos) << missing;
  EXPECT_NE(missing.find("gradient_echo, spin_echo"), std::string::npos) << missing;
  // Other types do not know it.
  EXPECT_NE(only_problem(k_minimal + "sequences:\n  - {name: T2w, type: spin_echo, TR_ms: 4000, TE_ms: 100, "
                                     "readout: spin_echo}\n")
                .find("found unknown key 'readout'"),
            std::string::npos);
}

TEST(ParseScene, BssfpEchoTimeDefaultsToHalfTheRepetitionTime) {
  const Scene s =
      *parse(k_minimal + "sequences:\n  - {name: bSSFP, type: bssfp, TR_ms: 5, flip_deg: 50}\n").scene;
  EXPECT_DOUBLE_EQ(s.mri.sequences.at(0).TE_ms, 2.5);
}

TEST(ParseScene, OrganReferencesAndNestingAreChecked) {
  const std::string two = k_minimal + R"(    - name: core
      tissue: csf
      inside: ball
      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 5}
)";
  ASSERT_TRUE(parse(two).scene);
  EXPECT_NE(only_problem(replaced(two, "inside: ball", "inside: nothing"))
                .find("anatomy.organs[1].inside: expected the name of an organ"),
            std::string::npos);
  EXPECT_NE(only_problem(replaced(two, "name: core", "name: ball"))
                .find("anatomy.organs[1].name: expected a unique organ name"),
            std::string::npos);
  const std::string cycle =
      replaced(two, "      tissue: white_matter\n", "      tissue: white_matter\n      inside: core\n");
  EXPECT_NE(only_problem(cycle).find("expected nesting without cycles"), std::string::npos);
}

TEST(ParseScene, DeformationReferencesExistingOrgans) {
  const std::string deformation = "deformation:\n  mode: quasi_static\n  fixed: [skull]\n";
  EXPECT_EQ(
      only_problem(k_minimal + deformation),
      "scene.yaml:15:11: deformation.fixed[0]: expected the name of an organ in this scene, found 'skull'");
  const std::string loads =
      "deformation:\n  mode: none\n  loads:\n    - {type: gravity, acceleration_m_s2: [0, 0, -9.81]}\n";
  EXPECT_NE(only_problem(k_minimal + loads).find("deformation.mode: expected quasi_static or dynamic"),
            std::string::npos);
}

TEST(ParseScene, TheGapTissueIsCsfWhenAMovedOrgansContainerHoldsCsfElseAirUnlessGiven) {
  // docs/scene-format.md, deformation.gap_tissue.
  const std::string box = replaced(k_minimal, "  organs:\n", R"(  organs:
    - {name: box, tissue: bone_cortical, shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 30}}
)");
  const std::string ball_in_box =
      replaced(box, "      tissue: white_matter\n", "      tissue: white_matter\n      inside: box\n");
  const std::string pushed = ball_in_box + R"(deformation:
  mode: quasi_static
  fixed: [box]
  loads: [{type: displacement, organ: ball, displacement_mm: [0, 0, -2], region: {center_mm: [0, 0, 20], radius_mm: 5}}]
)";
  SceneLoadResult result = parse(pushed);
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  EXPECT_EQ(result.scene->voxelization.gap_tissue, "");
  EXPECT_EQ(result.scene->voxelization.gap_fill, "air"); // no CSF in the box
  EXPECT_EQ(scene_settings_json(*result.scene)["deformation"]["gap_tissue"], "air");
  // A pocket of CSF next to the ball in the box: CSF fills the space the ball leaves.
  result = parse(replaced(pushed, "deformation:",
                          "    - {name: pocket, tissue: csf, inside: box, shape: {type: ellipsoid, "
                          "center_mm: [0, 0, 25], radii_mm: 2}}\ndeformation:"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  EXPECT_EQ(result.scene->voxelization.gap_fill, "csf");
  // Given: any tissue of the scene's organs; the default no longer applies.
  result = parse(pushed + "  gap_tissue: bone_cortical\n");
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  EXPECT_EQ(result.scene->voxelization.gap_fill, "bone_cortical");
  EXPECT_EQ(only_problem(pushed + "  gap_tissue: csf\n"),
            "scene.yaml:19:15: deformation.gap_tissue: expected air or the tissue of an organ of this scene "
            "(what fills the space a moved organ leaves), found 'csf'");
}

TEST(ParseScene, MeshFilesMustExist) {
  const std::string mesh = replaced(k_minimal, "{type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}",
                                    "{type: mesh, file: no-such-mesh.stl}");
  EXPECT_NE(
      only_problem(mesh).find("anatomy.organs[0].shape.file: expected an existing file, found no file at"),
      std::string::npos);
}

TEST(ParseScene, SettingsJsonRecordsEverySection) {
  const nlohmann::json j = scene_settings_json(*parse(k_minimal).scene);
  for (const char* key : {"name", "seed", "field_strength_T", "grid", "materials", "tissues", "anatomy",
                          "deformation", "voxelization", "sequences", "acquisition", "outputs"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["grid"]["voxel_size_mm"], nlohmann::json::array({2.0, 2.0, 4.0}));
}

TEST(LoadScene, AMissingFileIsOneClearProblem) {
  const SceneLoadResult result = load_scene("/no/such/scene.yaml");
  ASSERT_EQ(result.problems.size(), 1u);
  EXPECT_EQ(result.problems[0].format(), "/no/such/scene.yaml: expected a scene file, found no such file");
}

TEST(ParseScene, AcquiredVoxelSizeIsOneWayAndNoFinerThanTheGrid) {
  const SceneLoadResult ok = parse(k_minimal + "acquisition: {kspace: true, acquired_voxel_mm: [3, 2, 4]}\n");
  ASSERT_TRUE(ok.scene) << format_diagnostics(ok.problems);
  EXPECT_EQ(*ok.scene->mri.acquisition.acquired_voxel_mm, Eigen::Vector3d(3, 2, 4));
  EXPECT_FALSE(parse(k_minimal).scene->mri.acquisition.acquired_voxel_mm);

  std::string message =
      only_problem(k_minimal + "acquisition: {kspace: true, kspace_oversampling: 2, acquired_voxel_mm: 3}\n");
  EXPECT_NE(message.find("scene.yaml:13:"), std::string::npos) << message;
  EXPECT_NE(
      message.find("acquisition.acquired_voxel_mm: expected either acquired_voxel_mm or kspace_oversampling, "
                   "found both"),
      std::string::npos)
      << message;
  message = only_problem(k_minimal + "acquisition: {kspace: true, acquired_voxel_mm: [2, 2, 3]}\n");
  EXPECT_NE(
      message.find("acquisition.acquired_voxel_mm: expected acquired voxels no smaller than the grid's (4 mm "
                   "along axis 2; the grid samples the object), found 3 mm"),
      std::string::npos)
      << message;
}

TEST(ParseScene, PositionBasedSolversInAQuasiStaticSceneAreRejectedAtTheirLine) {
  const std::string message =
      only_problem(k_minimal + "deformation: {mode: quasi_static, solver: {method: xpbd}}\n");
  EXPECT_NE(message.find("scene.yaml:13:"), std::string::npos) << message;
  EXPECT_NE(message.find("deformation.solver.method: expected local_global, newton or jacobi_chebyshev for a "
                         "quasi_static scene (xpbd steps in time: it needs mode dynamic), found xpbd"),
            std::string::npos)
      << message;
  EXPECT_TRUE(
      parse(k_minimal + "deformation: {mode: quasi_static, solver: {method: jacobi_chebyshev}}\n").scene);
  EXPECT_TRUE(parse(k_minimal + "deformation: {mode: dynamic, solver: {method: xpbd}}\n").scene);
  EXPECT_TRUE(parse(k_minimal + "deformation: {mode: dynamic, solver: {method: gauss_seidel_pbd}}\n").scene);
}

TEST(ParseScene, ObstaclesAreReadWithTheirShapeKeysAndChecked) {
  const std::string obstacles = R"(deformation:
  mode: quasi_static
  load_steps: 3
  obstacles:
    - {type: half_space, point_mm: [0, 0, 30], normal: [0, 0, -2], displacement_mm: [0, 0, -5]}
    - {type: sphere, center_mm: [10, 0, 0], radius_mm: 4, motion: ramp, period_s: 0.5}
)";
  const SceneLoadResult result = parse(k_minimal + obstacles);
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  const DeformationSettings& d = result.scene->deformation;
  EXPECT_EQ(d.load_steps, 3);
  ASSERT_EQ(d.obstacles.size(), 2u);
  EXPECT_EQ(d.obstacles[0].shape, ObstacleShape::half_space);
  EXPECT_EQ(d.obstacles[0].normal, Eigen::Vector3d(0, 0, -1)); // normalized
  EXPECT_EQ(d.obstacles[0].displacement_mm, Eigen::Vector3d(0, 0, -5));
  EXPECT_EQ(d.obstacles[1].shape, ObstacleShape::sphere);
  EXPECT_EQ(d.obstacles[1].point_mm, Eigen::Vector3d(10, 0, 0));
  EXPECT_EQ(d.obstacles[1].radius_mm, 4.0);
  EXPECT_EQ(d.obstacles[1].motion, MotionProfile::ramp);
  const nlohmann::json j = scene_settings_json(*result.scene);
  EXPECT_EQ(j["deformation"]["obstacles"][1]["center_mm"], nlohmann::json::array({10.0, 0.0, 0.0}));

  EXPECT_EQ(
      only_problem(k_minimal + replaced(obstacles, "normal: [0, 0, -2]", "normal: [0, 0, 0]")),
      "scene.yaml:17:56: deformation.obstacles[0].normal: expected a non-zero normal (pointing out of the "
      "obstacle, towards the tissue), found [0, 0, 0]");
  EXPECT_NE(
      only_problem(k_minimal + replaced(obstacles, "radius_mm: 4", "radius_mm: -4"))
          .find("deformation.obstacles[1].radius_mm: expected a number in mm greater than 0, found '-4'"),
      std::string::npos);
  EXPECT_NE(only_problem(k_minimal + replaced(obstacles, "type: sphere, center_mm", "type: box, center_mm"))
                .find("deformation.obstacles[1].type: expected one of half_space, sphere, found 'box'"),
            std::string::npos);
  EXPECT_NE(
      only_problem(k_minimal + replaced(obstacles, "{type: sphere, center_mm: [10, 0, 0], radius_mm: 4,",
                                        "{type: sphere, radius_mm: 4,"))
          .find("deformation.obstacles[1].center_mm: expected a list of 3 numbers"),
      std::string::npos);
  EXPECT_NE(
      only_problem(k_minimal + replaced(obstacles, "mode: quasi_static", "mode: none"))
          .find("deformation.mode: expected quasi_static or dynamic when obstacles are given, found 'none'"),
      std::string::npos);
}

// A displacement load may turn its region about an axis (a clamp twisting a bar's end); a turn
// alone needs no displacement_mm, and a zero axis is an error at its key.
TEST(ParseScene, DisplacementLoadsMayTurnTheirRegionAboutAnAxis) {
  const std::string loads = R"(deformation:
  mode: quasi_static
  loads:
    - {type: displacement, organ: ball, region: {center_mm: [0, 0, 20], radius_mm: 5},
       rotation: {angle_deg: 30, axis: [0, 0, 2], center_mm: [0, 0, 20]}}
    - {type: displacement, organ: ball, displacement_mm: [0, 0, 0], region: {center_mm: [0, 0, -20], radius_mm: 5}}
)";
  const SceneLoadResult result = parse(k_minimal + loads);
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  const DeformationSettings& d = result.scene->deformation;
  ASSERT_EQ(d.loads.size(), 2u);
  EXPECT_EQ(d.loads[0].rotation_deg, 30.0);
  EXPECT_EQ(d.loads[0].rotation_axis, Eigen::Vector3d(0, 0, 1)); // normalized
  EXPECT_EQ(d.loads[0].rotation_center_mm, Eigen::Vector3d(0, 0, 20));
  EXPECT_EQ(d.loads[0].displacement_mm, Eigen::Vector3d::Zero());
  EXPECT_EQ(d.loads[1].rotation_deg, 0.0);
  const nlohmann::json j = scene_settings_json(*result.scene);
  EXPECT_EQ(j["deformation"]["loads"][0]["rotation"]["angle_deg"], 30.0);

  EXPECT_EQ(
      only_problem(k_minimal + replaced(loads, "axis: [0, 0, 2]", "axis: [0, 0, 0]")),
      "scene.yaml:17:40: deformation.loads[0].rotation.axis: expected a non-zero axis, found [0, 0, 0]");
  EXPECT_NE(only_problem(k_minimal + replaced(loads, "angle_deg: 30, ", ""))
                .find("deformation.loads[0].rotation.angle_deg: expected"),
            std::string::npos);
  EXPECT_NE(only_problem(k_minimal + replaced(loads, "displacement_mm: [0, 0, 0], ", ""))
                .find("deformation.loads[1].displacement_mm: expected"),
            std::string::npos);
}

TEST(ParseScene, CollisionsNameTwoDifferentOrgansOfTheScene) {
  const std::string collisions = R"(deformation:
  mode: quasi_static
  collisions:
    - {organs: [ball, ball]}
)";
  EXPECT_NE(only_problem(k_minimal + collisions)
                .find("deformation.collisions[0].organs: expected two different organs, found 'ball' twice"),
            std::string::npos);
  EXPECT_NE(
      only_problem(k_minimal + replaced(collisions, "[ball, ball]", "[ball, liver]"))
          .find("deformation.collisions[0].organs[1]: expected the name of an organ in this scene, found "
                "'liver'"),
      std::string::npos);
  EXPECT_NE(only_problem(k_minimal + replaced(collisions, "[ball, ball]", "[ball]"))
                .find("deformation.collisions[0].organs: expected two organ names, found 1"),
            std::string::npos);
  const std::string two =
      replaced(k_minimal, "      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}\n",
               "      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}\n"
               "    - {name: cube, tissue: white_matter, shape: {type: box, center_mm: [40, 0, "
               "0], size_mm: [10, 10, 10], cells: [2, 2, 2]}}\n");
  const SceneLoadResult result = parse(two + replaced(collisions, "[ball, ball]", "[ball, cube]"));
  ASSERT_TRUE(result.scene) << format_diagnostics(result.problems);
  ASSERT_EQ(result.scene->deformation.collisions.size(), 1u);
  EXPECT_EQ(result.scene->deformation.collisions[0].organs, (std::vector<std::string>{"ball", "cube"}));
  EXPECT_EQ(scene_settings_json(*result.scene)["deformation"]["collisions"][0]["organs"][1], "cube");
}

namespace {

/// A shape of `source` in YAML flow style, each key of its member given a valid value (files
/// made in `folder`); `left_out` names a key to leave out.
std::string shape_yaml(const ShapeSource& source, const std::filesystem::path& folder,
                       const std::string& left_out = "") {
  std::string yaml = std::string("{type: ") + source.name;
  for (const ShapeParameter& p : source.parameters) {
    if (p.key == left_out) continue;
    yaml += std::string(", ") + p.key + ": ";
    switch (p.kind) {
    case ShapeParameter::Kind::vector3: yaml += "[1.5, 2.5, 3.5]"; break;
    case ShapeParameter::Kind::extent2: yaml += "[1.5, 2.5]"; break;
    case ShapeParameter::Kind::cells: yaml += p.axes == 3 ? "[2, 3, 4]" : "[2, 3]"; break;
    case ShapeParameter::Kind::number: yaml += "1.5"; break;
    case ShapeParameter::Kind::labels: yaml += "3"; break;
    case ShapeParameter::Kind::file: {
      const std::filesystem::path file =
          folder / (std::string(source.name) + (p.extensions.empty() ? ".nii.gz" : p.extensions.front()));
      std::ofstream(file) << "data\n";
      yaml += file.string();
      break;
    }
    }
  }
  return yaml + "}";
}

std::string organ_with_shape(const ShapeSource& source, const std::string& shape) {
  return replaced(replaced(k_minimal, "{type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}", shape),
                  "      tissue: white_matter\n",
                  std::string("      tissue: white_matter\n") +
                      (source.has_interior ? "" : "      solid: false\n"));
}

} // namespace

TEST(ShapeSourceParsing, EveryMembersKeysParseAndAreRecordedInProvenance) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "phantasm-shape-sources";
  std::filesystem::create_directories(folder);
  for (const ShapeSource* source : shape_sources()) {
    const SceneLoadResult result = parse(organ_with_shape(*source, shape_yaml(*source, folder)));
    ASSERT_TRUE(result.scene) << source->name << ": " << format_diagnostics(result.problems);
    const ShapeSettings& shape = result.scene->anatomy.organs.at(0).shape;
    EXPECT_EQ(shape.kind, source->kind);
    const nlohmann::json j = scene_settings_json(*result.scene)["anatomy"]["organs"][0]["shape"];
    std::set<std::string> keys{"type"};
    for (const ShapeParameter& p : source->parameters) {
      keys.insert(p.key);
      if (p.kind == ShapeParameter::Kind::vector3) {
        EXPECT_EQ(shape.*p.vector, Eigen::Vector3d(1.5, 2.5, 3.5)) << source->name << "." << p.key;
      } else if (p.kind == ShapeParameter::Kind::number) {
        EXPECT_EQ(shape.*p.number, 1.5) << source->name << "." << p.key;
      }
    }
    std::set<std::string> written;
    for (const auto& item : j.items())
      written.insert(item.key());
    EXPECT_EQ(written, keys) << source->name;
    EXPECT_EQ(j["type"], source->name);
  }
  std::filesystem::remove_all(folder);
}

TEST(ShapeSourceParsing, EveryRequiredKeyLeftOutIsReportedAtItsPath) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / "phantasm-shape-sources-missing";
  std::filesystem::create_directories(folder);
  for (const ShapeSource* source : shape_sources()) {
    for (const ShapeParameter& p : source->parameters) {
      if (!p.required) continue;
      const std::string problem = only_problem(organ_with_shape(*source, shape_yaml(*source, folder, p.key)));
      EXPECT_NE(problem.find(std::string("anatomy.organs[0].shape.") + p.key + ": expected"),
                std::string::npos)
          << source->name << ": " << problem;
      EXPECT_NE(problem.find("found no such key"), std::string::npos) << problem;
    }
  }
  std::filesystem::remove_all(folder);
}

// The shipped Colin scenes' grids: sizes whose prime factors FFTW transforms fast (the images'
// k-space acquisition took about twice as long on 189 x 217 x 185, whose 31 and 37 it cannot
// split, and about four times per voxel on 203 x 237 x 197), with the voxel centres on the
// template's (whole millimetres, the labels' own voxel centres), holding the template's head.
TEST(ShippedScenes, TheColinGridsHaveFastTransformSizesOnTheTemplatesVoxelCentres) {
  for (const std::string name : {"colin-head", "colin-atrophy"}) {
    const SceneLoadResult result =
        load_scene(std::filesystem::path(PHANTASM_SOURCE_DIR) / "data-synthetic" / (name + ".yaml"));
    ASSERT_TRUE(result.scene) << name << "\n" << format_diagnostics(result.problems);
    const ImageGrid grid = result.scene->grid.grid();
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(largest_prime_factor(grid.dims[a]), 13) << name << " axis " << a << ": " << grid.dims[a];
      // Every voxel centre a whole millimetre, as the template's.
      const double first = grid.world_from_index(Eigen::Vector3d::Zero())[a];
      EXPECT_EQ(first, std::round(first)) << name << " axis " << a;
      EXPECT_EQ(grid.spacing_mm[a], 1.0) << name;
    }
    // The template's head (x -90..90, y -119..91, z -71..102 mm) with its two background voxels.
    const Eigen::Vector3d low = grid.world_from_index(Eigen::Vector3d::Zero());
    const Eigen::Vector3d high = grid.world_from_index((grid.dims - Eigen::Vector3i::Ones()).cast<double>());
    EXPECT_TRUE((low.array() <= Eigen::Array3d(-92, -121, -73)).all()) << name << ": " << low.transpose();
    EXPECT_TRUE((high.array() >= Eigen::Array3d(92, 93, 104)).all()) << name << ": " << high.transpose();
  }
}
