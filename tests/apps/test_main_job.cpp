// The procedural head (data-synthetic/head.yaml) end to end at full size, the README's second
// scene. The main job's own scene, data-synthetic/colin-head.yaml, takes minutes at full size: its
// coarse run is tests/atlas/test_colin_head_scene.cpp.

#include "core/sha256.hpp"
#include "geometry/tet_quality.hpp"
#include "io/dataset_layout.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"
#include "tests/apps/cli_fixtures.hpp"
#include "tests/support/subprocess.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

using namespace phantasm::testing;
namespace fs = std::filesystem;

// The procedural head's dataset, as the README describes it.
TEST(RunCommand, WritesTheHeadDatasetWithOrganMeshesAndProvenance) {
  const fs::path out = fresh_folder("head") / "out";
  const CommandResult result = run_command({k_phantasm, "run", k_head_scene.string(), "-o", out.string()});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto description = nlohmann::json::parse(read_file(out / "dataset_description.json"));
  EXPECT_EQ(description["Name"], "head");
  EXPECT_EQ(description["DatasetType"], "raw");
  EXPECT_TRUE(fs::is_directory(out / "sub-01" / "ses-ref" / "anat"));
  EXPECT_TRUE(fs::is_directory(out / "sub-01" / "ses-def" / "anat"));

  const fs::path derivatives = out / "derivatives" / "phantasm";
  EXPECT_EQ(nlohmann::json::parse(read_file(derivatives / "dataset_description.json"))["DatasetType"],
            "derivative");
  const std::string dseg = read_file(derivatives / "dseg.tsv");
  EXPECT_EQ(dseg.rfind("index\tname\ttissue\torgan_entity\ttissue_entity\n"
                       "0\tbackground\tbackground\tbackground\tbackground\n1\tscalp\tskin\tscalp\tskin\n",
                       0),
            0u)
      << dseg;
  EXPECT_EQ(std::count(dseg.begin(), dseg.end(), '\n'), 10); // header, background, 7 organs, the gap
  EXPECT_NE(dseg.find("\n8\tgap\tcsf\tgap\tcsf\n"), std::string::npos) << dseg;
  EXPECT_NE(dseg.find("\tventricle_left\tcsf\tventricleLeft\tcsf\n"), std::string::npos) << dseg;

  // Every organ of the head is solid: a closed surface (.vtp) and a tet mesh (.vtu) each, which
  // VTK reads back; the surface encloses about the tet mesh's volume. In the deformed state the
  // fixed scalp and skull have not moved, the grey matter has (the retractor), no tet inverted.
  const phantasm::DatasetLayout layout(out, "01");
  const auto ref = phantasm::PhantomState::reference, def = phantasm::PhantomState::deformed;
  for (const std::string organ :
       {"scalp", "skull", "csf", "grey_matter", "white_matter", "ventricle_left", "ventricle_right"}) {
    SCOPED_TRACE(organ);
    const phantasm::TriangleMesh surface = phantasm::read_triangle_mesh(layout.mesh(ref, organ));
    EXPECT_NO_THROW(phantasm::check_closed_manifold(surface, organ));
    const phantasm::TetMesh solid = phantasm::read_vtu(layout.tet_mesh(ref, organ));
    double volume = 0.0;
    for (Eigen::Index t = 0; t < solid.tets.rows(); ++t) {
      ASSERT_GT(phantasm::tet_volume(solid, t), 0.0);
      volume += phantasm::tet_volume(solid, t);
    }
    EXPECT_NEAR(phantasm::enclosed_volume(surface) / volume, 1.0, 0.02);
    const phantasm::TetMesh deformed = phantasm::read_vtu(layout.tet_mesh(def, organ));
    ASSERT_EQ(deformed.tets, solid.tets);
    for (Eigen::Index t = 0; t < deformed.tets.rows(); ++t)
      ASSERT_GT(phantasm::tet_volume(deformed, t), 0.0);
    const double moved = (deformed.vertices - solid.vertices).rowwise().norm().maxCoeff();
    if (organ == "scalp" || organ == "skull") {
      EXPECT_EQ(moved, 0.0);
    }
    if (organ == "grey_matter") {
      EXPECT_GT(moved, 3.0);
    }
    EXPECT_NO_THROW(
        phantasm::check_closed_manifold(phantasm::read_triangle_mesh(layout.mesh(def, organ)), organ));
  }

  const auto provenance = nlohmann::json::parse(read_file(derivatives / "sub-01" / "provenance.json"));
  EXPECT_EQ(provenance["scene"]["sha256"], phantasm::sha256_hex(read_file(k_head_scene)));
  EXPECT_EQ(provenance["seed"], 1);
  EXPECT_EQ(provenance["settings"]["deformation"]["solver"]["method"], "local_global");
  ASSERT_EQ(provenance["stages"].size(), 4u);
  EXPECT_EQ(provenance["stages"][0]["stage"], "anatomy");
  EXPECT_EQ(provenance["stages"][0]["status"], "done");
  EXPECT_LT(provenance["stages"][0]["accuracy"]["white_matter fit to source max mm"].get<double>(), 3.0);
  EXPECT_EQ(provenance["files"].size(), 115u); // every file but provenance.json itself
  // The head was deformed: one quasi-static solve, stopped by a criterion, its residual reported.
  EXPECT_EQ(provenance["stages"][1]["status"], "done");
  ASSERT_EQ(provenance["solves"].size(), 1u);
  EXPECT_NE(provenance["solves"][0]["stopped_by"], "max_iterations");
  EXPECT_LT(provenance["solves"][0]["residual_N"].get<double>(), 1.0);
  EXPECT_LT(provenance["stages"][1]["accuracy"]["displacement load error mm"].get<double>(), 0.05);
  EXPECT_EQ(read_file(derivatives / "sub-01" / "scene.yaml"), read_file(k_head_scene));
  const std::string log = read_file(derivatives / "sub-01" / "log.txt");
  EXPECT_NE(log.find("[sim] scalp: held fixed"), std::string::npos) << log;
  EXPECT_NE(log.find("[voxelize] skipped: .vdb grids"), std::string::npos) << log;
  EXPECT_NE(log.find("[anatomy] organ meshes for ParaView: surfaces tessellated within 0.2 mm"),
            std::string::npos)
      << log;
}
