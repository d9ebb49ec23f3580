// Every scene shipped in data-synthetic/ is physically sound (#16): run on a coarse grid by the
// phantasm command, it exits 0, its solves converge, no tet inverts (det F > 0 from the tet
// meshes of both states), every organ that moved stays inside the field of view and no written
// volume holds a NaN. One test per scene, so that ctest
// runs them in parallel and names the scene that fails.

#include "io/dataset_layout.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/coarse_runs.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

/// The shipped scenes' file stems, sorted; sweep files (a `phantasm_sweep` key) are sweeps, not
/// scenes. colin-head.yaml has its own coarse run with the same checks and coarse base meshes
/// (tests/atlas/test_colin_head_scene.cpp): its 2000-triangle label surfaces would take minutes
/// here; colin-atrophy.yaml has the same anatomy, and its growth loads are checked on a smaller
/// scene of an atlas region (tests/sim/test_growth_regions.cpp). The source folder comes from the macro (not
/// k_source_dir): the test list is built during static initialization.
std::vector<std::string> shipped_scenes() {
  std::vector<std::string> scenes;
  for (const auto& entry : fs::directory_iterator(fs::path(PHANTASM_SOURCE_DIR) / "data-synthetic")) {
    const std::string stem = entry.path().stem().string();
    if (entry.path().extension() != ".yaml" || stem == "colin-head" || stem == "colin-atrophy") continue;
    if (YAML::LoadFile(entry.path().string())["phantasm_sweep"]) continue;
    scenes.push_back(entry.path().stem().string());
  }
  std::sort(scenes.begin(), scenes.end());
  return scenes;
}

/// Whether a point (RAS mm) lies inside the grid's field of view: within half a voxel of the
/// outermost voxel centres.
bool inside_grid(const ImageGrid& grid, const Eigen::Vector3d& x) {
  const Eigen::Vector4d index = grid.world_from_voxel.inverse() * x.homogeneous();
  for (int a = 0; a < 3; ++a)
    if (index[a] < -0.5 || index[a] > grid.dims[a] - 0.5) return false;
  return true;
}

/// The smallest det F = det(D_def D_ref^-1) over the tets of a mesh in its two states.
double smallest_det_f(const TetMesh& rest, const TetMesh& moved) {
  double smallest = 1e300;
  for (Eigen::Index t = 0; t < rest.tets.rows(); ++t) {
    Eigen::Matrix3d a, b;
    for (int e = 0; e < 3; ++e) {
      a.col(e) = (rest.vertices.row(rest.tets(t, e + 1)) - rest.vertices.row(rest.tets(t, 0))).transpose();
      b.col(e) = (moved.vertices.row(rest.tets(t, e + 1)) - moved.vertices.row(rest.tets(t, 0))).transpose();
    }
    smallest = std::min(smallest, (b * a.inverse()).determinant());
  }
  return smallest;
}

/// The values of a written volume: displacement fields are 5-D vector images, the rest 3-D.
std::vector<double> volume_values(const fs::path& file) {
  const std::string name = file.filename().string();
  const bool field = name.find("_xfm.nii") != std::string::npos;
  return field ? read_nifti_vectors(file).values : read_nifti(file).values;
}

class ShippedScene : public ::testing::TestWithParam<std::string> {};

} // namespace

TEST(ShippedScenes, AreFound) {
  // Guards the parameterized test below against an empty list (a moved folder).
  EXPECT_GE(shipped_scenes().size(), 5u);
}

TEST_P(ShippedScene, IsPhysicallySoundOnACoarseGrid) {
  const fs::path scene = k_source_dir / "data-synthetic" / (GetParam() + ".yaml");
  // The run the cost estimate's test measures too (tests/support/coarse_runs.hpp): it exited 0
  // (a run that did not fails here).
  const CoarseRun run = shared_coarse_run(scene);
  ASSERT_FALSE(::testing::Test::HasFailure());
  const fs::path out = run.out;
  RecordProperty("run_seconds", std::to_string(run.measured.wall_seconds));

  const DatasetLayout layout(out, YAML::LoadFile(scene.string())["outputs"]["subject"].as<std::string>("01"));
  const auto provenance = nlohmann::json::parse(read_file(layout.provenance()));

  // Every solve converged at the scene's settings (docs/deformation.md, the stopping test); had
  // one not, the run must say so loudly: a warning on stderr and in provenance.
  bool all_converged = true;
  for (const auto& solve : provenance.value("solves", nlohmann::json::array())) {
    ASSERT_TRUE(solve.contains("converged")) << solve.dump();
    all_converged = all_converged && solve.at("converged").get<bool>();
  }
  EXPECT_TRUE(all_converged) << provenance.at("solves").dump();
  if (!all_converged) {
    EXPECT_NE(run.measured.err.find("warning"), std::string::npos) << run.measured.err;
    EXPECT_FALSE(provenance.value("warnings", nlohmann::json::array()).empty());
  }

  ImageGrid grid;
  read_nifti_labels(layout.dseg(PhantomState::reference), &grid);
  for (const auto& organ_node : YAML::LoadFile(scene.string())["anatomy"]["organs"]) {
    const std::string organ = organ_node["name"].as<std::string>();
    SCOPED_TRACE(organ);
    // No inverted tet.
    const fs::path ref_tets = layout.tet_mesh(PhantomState::reference, organ);
    const fs::path def_tets = layout.tet_mesh(PhantomState::deformed, organ);
    if (fs::exists(ref_tets) && fs::exists(def_tets)) {
      const TetMesh rest = read_vtu(ref_tets), moved = read_vtu(def_tets);
      ASSERT_EQ(rest.vertices.rows(), moved.vertices.rows());
      EXPECT_GT(smallest_det_f(rest, moved), 0.0) << "an inverted tet";
    }
    // An organ the deformation moved keeps its bounding box inside the field of view (organs
    // that stay may be cut by it: the abdomen's body is longer than its field of view).
    const fs::path ref_surface = layout.mesh(PhantomState::reference, organ);
    const fs::path def_surface = layout.mesh(PhantomState::deformed, organ);
    if (!fs::exists(ref_surface) || !fs::exists(def_surface)) continue;
    const TriangleMesh rest = read_triangle_mesh(ref_surface), moved = read_triangle_mesh(def_surface);
    if (rest.vertices.rows() == moved.vertices.rows() &&
        (rest.vertices - moved.vertices).cwiseAbs().maxCoeff() < 1e-9)
      continue;
    const Eigen::Vector3d low = moved.vertices.colwise().minCoeff(),
                          high = moved.vertices.colwise().maxCoeff();
    bool inside = true;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d x(corner & 1 ? high.x() : low.x(), corner & 2 ? high.y() : low.y(),
                              corner & 4 ? high.z() : low.z());
      inside = inside && inside_grid(grid, x);
    }
    EXPECT_TRUE(inside) << "bounding box [" << low.transpose() << "] .. [" << high.transpose() << "] mm";
  }

  // No NaN (nor infinity) in any written volume.
  std::size_t volumes = 0;
  for (const auto& entry : fs::recursive_directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || name.size() < 7 || name.substr(name.size() - 7) != ".nii.gz") continue;
    ++volumes;
    const std::vector<double> values = volume_values(entry.path());
    const auto bad = std::count_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); });
    EXPECT_EQ(bad, 0) << entry.path();
  }
  EXPECT_GT(volumes, 5u);
}

INSTANTIATE_TEST_SUITE_P(DataSynthetic, ShippedScene, ::testing::ValuesIn(shipped_scenes()),
                         [](const ::testing::TestParamInfo<std::string>& scene) {
                           std::string name = scene.param;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });
