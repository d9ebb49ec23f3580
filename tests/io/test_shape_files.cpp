// Organs made of files: a triangle mesh (STL) and labels of a NIfTI label volume, read by io
// and built into a phantom by anatomy.

#include "anatomy/phantom.hpp"
#include "core/error.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "io/shape_files.hpp"
#include "scene/scene.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <thread>
#include <vector>

using namespace phantasm;
using phantasm::testing::fresh_folder;
namespace fs = std::filesystem;

namespace {

constexpr double k_pi = 3.14159265358979323846;

/// A label volume on a 1 mm grid: label 1 a ball of radius 12 mm at (-15, 0, 0), label 2 a ball
/// of radius 9 mm at (15, 0, 0).
void write_two_balls(const fs::path& path) {
  ImageGrid grid;
  grid.dims = {64, 40, 40};
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-31.5, -19.5, -19.5);
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  std::size_t i = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int x = 0; x < grid.dims.x(); ++x, ++i) {
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(x, j, k));
        if ((p - Eigen::Vector3d(-15, 0, 0)).norm() < 12.0) labels[i] = 1;
        if ((p - Eigen::Vector3d(15, 0, 0)).norm() < 9.0) labels[i] = 2;
      }
  write_nifti_labels(path, grid, labels);
}

Scene scene_in(const fs::path& folder, const std::string& organs) {
  const std::string text = "phantasm: 1\nname: files\nseed: 1\nfield_strength_T: 3.0\n"
                           "grid: {field_of_view_mm: 96, voxel_size_mm: 2}\n"
                           "anatomy:\n  base_mesh_triangles: 80\n  organs:\n" +
                           organs;
  const SceneLoadResult result = parse_scene(text, folder / "scene.yaml");
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
  return result.scene ? *result.scene : Scene{};
}

/// Writes folder/ball.vtp (a 20 mm sphere of 1280 triangles: a dense target for 80 patches) and
/// folder/labels.nii.gz (write_two_balls); returns the sphere.
TriangleMesh write_ball_and_labels(const fs::path& folder) {
  TriangleMesh ball = unit_icosphere(3);
  ball.vertices *= 20.0;
  write_vtp(folder / "ball.vtp", ball);
  write_two_balls(folder / "labels.nii.gz");
  return ball;
}

} // namespace

TEST(ShapeFiles, MeshAndLabelVolumeOrgansBecomePatchSurfacesOfTheirVolume) {
  const fs::path folder = fresh_folder("shape-files");
  const TriangleMesh ball = write_ball_and_labels(folder);
  const Scene scene = scene_in(
      folder, R"(    - {name: ball, tissue: white_matter, solid: false, shape: {type: mesh, file: ball.vtp}}
    - {name: left, tissue: gray_matter, solid: false, shape: {type: label_volume, file: labels.nii.gz, label: 1}}
    - {name: right, tissue: csf, shape: {type: label_volume, file: labels.nii.gz, label: 2}}
)");
  const std::map<std::string, ShapeData> files = read_shape_files(scene.anatomy);
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files.at("ball").mesh->face_count(), 1280);
  EXPECT_EQ(files.at("left").labels->size(), 64u * 40u * 40u);

  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, files, quiet);
  // The mesh organ follows its dense mesh; the label organs the balls the voxels sample (the
  // 1/2-level of trilinear interpolated indicators lies within about half a voxel of the sphere).
  EXPECT_NEAR(phantom.find("ball")->surface->volume() / enclosed_volume(ball), 1.0, 1e-3);
  EXPECT_LT(phantom.find("ball")->fit.source_max_mm, 1.0);
  EXPECT_NEAR(phantom.find("left")->surface->volume() / (4.0 / 3.0 * k_pi * 12 * 12 * 12), 1.0, 0.05);
  EXPECT_NEAR(phantom.find("right")->surface->volume() / (4.0 / 3.0 * k_pi * 9 * 9 * 9), 1.0, 0.07);
  ASSERT_TRUE(phantom.find("right")->solid);
  for (Eigen::Index t = 0; t < phantom.find("right")->solid->tets.rows(); ++t)
    ASSERT_GT(tet_volume(*phantom.find("right")->solid, t), 0.0);
}

// The phantom read back from its geometry (the anatomy cache) makes its file shapes' targets on
// their first use: they answer every question as the built phantom's targets do, bit for bit,
// from any thread.
TEST(ShapeFiles, ADecodedPhantomsFileTargetsAnswerAsTheBuiltOnes) {
  const fs::path folder = fresh_folder("shape-files-decoded");
  write_ball_and_labels(folder);
  const Scene scene = scene_in(
      folder, R"(    - {name: ball, tissue: white_matter, solid: false, shape: {type: mesh, file: ball.vtp}}
    - {name: left, tissue: gray_matter, solid: false, shape: {type: label_volume, file: labels.nii.gz, label: 1}}
)");
  const std::map<std::string, ShapeData> files = read_shape_files(scene.anatomy);
  Reporter quiet = Reporter::silent();
  const Phantom built = build_phantom(scene.anatomy, files, quiet);
  const Phantom read = phantom_from_geometry(scene.anatomy, files, encode_organ_geometry(built), quiet);
  ASSERT_EQ(read.organs.size(), 2u);
  for (std::size_t o = 0; o < 2; ++o) {
    const ImplicitShape& a = *built.organs[o].target;
    const ImplicitShape& b = *read.organs[o].target;
    SCOPED_TRACE(built.organs[o].name);
    // Asked first from several threads at once: one of them makes it, the others wait for it.
    std::vector<double> first(8);
    std::vector<std::thread> threads;
    for (int n = 0; n < 8; ++n)
      threads.emplace_back(
          [&, n] { first[static_cast<std::size_t>(n)] = b.value(Eigen::Vector3d(2.5 * n, 1.0, -3.0)); });
    for (std::thread& thread : threads)
      thread.join();
    for (int n = 0; n < 8; ++n)
      EXPECT_EQ(first[static_cast<std::size_t>(n)], a.value(Eigen::Vector3d(2.5 * n, 1.0, -3.0)));
    EXPECT_EQ(b.volume(), a.volume());
    EXPECT_EQ(b.center(), a.center());
    EXPECT_EQ(b.bounding_radius(), a.bounding_radius());
    EXPECT_EQ(b.star_shaped(), a.star_shaped());
    EXPECT_EQ(b.smoothed_indicator(), a.smoothed_indicator());
    for (double x = -30.0; x <= 30.0; x += 7.3)
      for (double y = -24.0; y <= 24.0; y += 6.1)
        for (double z = -24.0; z <= 24.0; z += 5.9) {
          const Eigen::Vector3d p(x, y, z);
          ASSERT_EQ(b.value(p), a.value(p)) << p.transpose();
          ASSERT_EQ(b.gradient(p), a.gradient(p)) << p.transpose();
        }
  }
}

TEST(ShapeFiles, ALabelMissingFromItsVolumeIsReportedAtItsSceneField) {
  const fs::path folder = fresh_folder("shape-files-missing");
  write_two_balls(folder / "labels.nii.gz");
  const Scene scene = scene_in(
      folder,
      "    - {name: gone, tissue: csf, shape: {type: label_volume, file: labels.nii.gz, label: 7}}\n");
  try {
    read_shape_files(scene.anatomy);
    FAIL() << "no error";
  } catch (const SettingError& error) {
    // The stage names the setting; the scene knows where it was written.
    EXPECT_EQ(error.key_path(), "anatomy.organs[0].shape.label");
    EXPECT_NE(error.message().find("expected voxels of label 7 (organ gone), found none"), std::string::npos)
        << error.message();
    const SourceLocation where = scene.location_of(error.key_path());
    EXPECT_NE(where.file.find("scene.yaml"), std::string::npos) << where.file;
    EXPECT_EQ(where.line, 9); // the organ's line
  }
}

TEST(ShapeFiles, AnOpenMeshIsRejectedWithTheDefectNamed) {
  const fs::path folder = fresh_folder("shape-files-open");
  TriangleMesh ball = unit_icosphere(2);
  ball.vertices *= 20.0;
  TriangleMesh open = ball;
  open.faces = ball.faces.topRows(ball.face_count() - 1);
  write_vtp(folder / "open.vtp", open);
  const Scene scene =
      scene_in(folder, "    - {name: cup, tissue: csf, shape: {type: mesh, file: open.vtp}}\n");
  Reporter quiet = Reporter::silent();
  try {
    build_phantom(scene.anatomy, read_shape_files(scene.anatomy), quiet);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("open edge"), std::string::npos) << error.what();
  }
}

namespace {

/// The two balls as an atlas would give them: label 1 "big", label 2 "small", on a grid whose
/// origin is shifted by `offset_mm`.
AtlasLabelVolume two_ball_atlas(const fs::path& folder,
                                const Eigen::Vector3d& offset_mm = Eigen::Vector3d::Zero()) {
  write_two_balls(folder / "atlas.nii.gz");
  AtlasLabelVolume volume;
  volume.labels = std::make_shared<const std::vector<std::int32_t>>(
      read_nifti_labels(folder / "atlas.nii.gz", &volume.grid));
  volume.grid.world_from_voxel.topRightCorner<3, 1>() += offset_mm;
  volume.names = {{"big", 1}, {"small", 2}};
  volume.source = "atlas test";
  return volume;
}

/// The message of the SettingError that reading the organs' shapes throws, with its key path.
std::pair<std::string, std::string> shape_error(const Scene& scene, const AtlasLoader& atlases,
                                                const std::optional<ImageGrid>& grid = std::nullopt) {
  try {
    read_shape_files(scene.anatomy, atlases, grid);
  } catch (const SettingError& error) {
    return {error.key_path(), error.message()};
  }
  return {"", "no error"};
}

} // namespace

TEST(ShapeFiles, AtlasLabelsAreNamedAndNestedOrgansAreUnitedIntoTheirContainer) {
  const fs::path folder = fresh_folder("shape-files-atlas");
  int derivations = 0;
  const AtlasLoader atlases = [&](const std::string& name) {
    EXPECT_EQ(name, "colin27");
    ++derivations;
    return two_ball_atlas(folder);
  };
  // "outer" holds both balls (label 2 by number, "small" by name) and contains "inner".
  const Scene scene = scene_in(
      folder, R"(    - {name: outer, tissue: csf, shape: {type: label_volume, atlas: colin27, label: big}}
    - {name: inner, tissue: gray_matter, inside: outer, shape: {type: label_volume, atlas: colin27, label: [small]}}
    - {name: both, tissue: csf, solid: false, shape: {type: label_volume, atlas: colin27, label: [1, small]}}
)");
  const std::map<std::string, ShapeData> files = read_shape_files(scene.anatomy, atlases);
  EXPECT_EQ(derivations, 1); // once per run, shared by the organs
  EXPECT_EQ(files.at("outer").target_labels, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(files.at("inner").target_labels, (std::vector<std::int32_t>{2}));
  EXPECT_EQ(files.at("both").target_labels, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(files.at("outer").labels, files.at("inner").labels); // one copy of the volume
}

TEST(ShapeFiles, AnUnknownAtlasLabelNameIsReportedWithTheAtlasAndItsNames) {
  const fs::path folder = fresh_folder("shape-files-atlas-name");
  const AtlasLoader atlases = [&](const std::string&) { return two_ball_atlas(folder); };
  const Scene scene = scene_in(
      folder, "    - {name: gm, tissue: csf, shape: {type: label_volume, atlas: colin27, label: grey}}\n");
  const auto [key, message] = shape_error(scene, atlases);
  EXPECT_EQ(key, "anatomy.organs[0].shape.label");
  EXPECT_NE(message.find("atlas test: expected a label of its table (big, small) for organ gm, found 'grey'"),
            std::string::npos)
      << message;
}

TEST(ShapeFiles, ALabelOnTheVolumesEdgeIsRejectedNamingFileAndLabel) {
  const fs::path folder = fresh_folder("shape-files-edge");
  ImageGrid grid;
  grid.dims = {20, 20, 20};
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  for (int k = 0; k < 20; ++k)
    for (int j = 5; j < 15; ++j)
      for (int i = 5; i < 15; ++i)
        labels[voxel_index(grid.dims, i, j, k)] = 3; // a bar through the volume along k
  write_nifti_labels(folder / "bar.nii.gz", grid, labels);
  const Scene scene = scene_in(
      folder, "    - {name: bar, tissue: csf, shape: {type: label_volume, file: bar.nii.gz, label: 3}}\n");
  const auto [key, message] = shape_error(scene, {});
  EXPECT_EQ(key, "anatomy.organs[0].shape.label");
  EXPECT_NE(message.find("bar.nii.gz: label 3 (organ bar) touches the volume's edge"), std::string::npos)
      << message;
}

TEST(ShapeFiles, LabelsOutsideTheSceneGridAreRejected) {
  const fs::path folder = fresh_folder("shape-files-outside");
  const AtlasLoader atlases = [&](const std::string&) {
    return two_ball_atlas(folder, Eigen::Vector3d(500, 0, 0));
  };
  const Scene scene = scene_in(
      folder, "    - {name: ball, tissue: csf, shape: {type: label_volume, atlas: colin27, label: big}}\n");
  const auto [key, message] = shape_error(scene, atlases, scene.grid.grid());
  EXPECT_EQ(key, "anatomy.organs[0].shape.label");
  EXPECT_NE(message.find("atlas test: the voxels of organ ball"), std::string::npos) << message;
  EXPECT_NE(message.find("lie outside the scene grid"), std::string::npos) << message;
  // The same volume where the grid is: accepted.
  EXPECT_EQ(shape_error(
                scene, [&](const std::string&) { return two_ball_atlas(folder); }, scene.grid.grid())
                .second,
            "no error");
}

TEST(ShapeFiles, AtlasAndFileTogetherOrALabelNameWithAFileAreSceneErrors) {
  const fs::path folder = fresh_folder("shape-files-atlas-scene");
  write_two_balls(folder / "labels.nii.gz");
  const std::string head = "phantasm: 1\nname: files\nseed: 1\nfield_strength_T: 3.0\n"
                           "grid: {field_of_view_mm: 96, voxel_size_mm: 2}\nanatomy:\n  organs:\n";
  const SceneLoadResult both = parse_scene(
      head + "    - {name: a, tissue: csf, shape: {type: label_volume, atlas: colin27, file: labels.nii.gz, "
             "label: csf}}\n",
      folder / "scene.yaml");
  ASSERT_FALSE(both.scene);
  EXPECT_NE(format_diagnostics(both.problems).find("expected either file or atlas, found both"),
            std::string::npos)
      << format_diagnostics(both.problems);
  const SceneLoadResult named = parse_scene(
      head + "    - {name: a, tissue: csf, shape: {type: label_volume, file: labels.nii.gz, label: csf}}\n",
      folder / "scene.yaml");
  ASSERT_FALSE(named.scene);
  EXPECT_NE(format_diagnostics(named.problems).find("anatomy.organs[0].shape.label: expected an integer"),
            std::string::npos)
      << format_diagnostics(named.problems);
  const SceneLoadResult unknown = parse_scene(
      head + "    - {name: a, tissue: csf, shape: {type: label_volume, atlas: mni152, label: csf}}\n",
      folder / "scene.yaml");
  ASSERT_FALSE(unknown.scene);
}
