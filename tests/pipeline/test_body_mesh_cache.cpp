// The body mesh cache (pipeline/body_mesh_cache.hpp): a stored mesh decodes to the bytes it was
// stored from and refuses damaged bytes; runs of a scene whose body holds nested organs write the
// same files without the cache, with it cold (meshing and storing the body) and warm (reading it);
// a damaged entry is meshed again; the inputs the deformation stage names change with what
// shapes the mesh only.

#include "anatomy/phantom.hpp"
#include "core/byte_codec.hpp"
#include "pipeline/body_mesh_cache.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <functional>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_balls =
    fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "population-balls.yaml";

} // namespace

// Two tets with subdomains and repairs: decoded, the same mesh; cut short, with bytes after it or
// with a tet naming a vertex the mesh does not have, DamagedBytes.
TEST(BodyMeshCache, DecodesWhatWasEncodedAndRefusesDamagedBytes) {
  NestedBodyMesh mesh;
  mesh.mesh.vertices.resize(5, 3);
  mesh.mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1.5;
  mesh.mesh.tets.resize(2, 4);
  mesh.mesh.tets << 0, 1, 2, 3, 1, 2, 3, 4;
  mesh.mesh.boundary_faces.resize(1, 3);
  mesh.mesh.boundary_faces << 0, 2, 1;
  mesh.mesh.subdomains.resize(2);
  mesh.mesh.subdomains << 0, 1;
  mesh.repairs = {3, 1, 4, 1, 5, 9};
  const std::string bytes = encode_nested_body_mesh(mesh);
  const NestedBodyMesh read = decode_nested_body_mesh(bytes);
  EXPECT_TRUE(read.mesh.vertices == mesh.mesh.vertices);
  EXPECT_TRUE(read.mesh.tets == mesh.mesh.tets);
  EXPECT_TRUE(read.mesh.boundary_faces == mesh.mesh.boundary_faces);
  EXPECT_TRUE(read.mesh.subdomains == mesh.mesh.subdomains);
  EXPECT_EQ(read.repairs.vertex_moves, 3);
  EXPECT_EQ(read.repairs.collapses, 9);
  EXPECT_TRUE(encode_nested_body_mesh(read) == bytes);
  EXPECT_THROW(decode_nested_body_mesh(std::string_view(bytes).substr(0, bytes.size() - 1)), DamagedBytes);
  EXPECT_THROW(decode_nested_body_mesh(bytes + "x"), DamagedBytes);
  NestedBodyMesh wrong = mesh;
  wrong.mesh.tets(1, 3) = 5;
  EXPECT_THROW(decode_nested_body_mesh(encode_nested_body_mesh(wrong)), DamagedBytes);
  // The key: a SHA-256 of the anatomy's key and the inputs, each of which changes it; none
  // without an anatomy key (no cache).
  const std::string key = body_mesh_cache_key("anatomy", "inputs");
  EXPECT_EQ(key.size(), 64u);
  EXPECT_NE(body_mesh_cache_key("anatomy2", "inputs"), key);
  EXPECT_NE(body_mesh_cache_key("anatomy", "inputs2"), key);
  EXPECT_TRUE(body_mesh_cache_key("", "inputs").empty());
}

// Runs of two balls in a layer (one tet mesh of the three, a growth load on each ball) without
// the cache, cold and warm write the same bytes in every image, label volume, field and
// landmark file; the cold and warm logs are the same and name the entry. A damaged entry is
// meshed again (a line, no stage warning), with the same files, and stored anew.
TEST(BodyMeshCache, RunsWithTheCacheColdWarmAndWithoutWriteTheSameFiles) {
  const Scene scene = scene_of(k_balls);
  const fs::path folder = fresh_folder("body-mesh-cache");
  const fs::path cache = folder / "cache";
  const auto run = [&](const std::string& name, const fs::path& cache_folder) {
    return run_with_cache(scene, folder / name, cache_folder);
  };
  const auto [none_summary, none] = run("none", {});
  const auto [cold_summary, cold] = run("cold", cache);
  const std::vector<fs::path> entries = cache_entries(cache, "body-mesh-");
  ASSERT_EQ(entries.size(), 1u);
  const auto [warm_summary, warm] = run("warm", cache);
  EXPECT_EQ(cache_entries(cache, "body-mesh-"), entries); // read, not stored again
  EXPECT_TRUE(contains(cold_summary.stages[1].modelled, "kept in the body mesh cache as entry"));
  EXPECT_EQ(warm_summary.stages[1].modelled, cold_summary.stages[1].modelled);
  ASSERT_GT(none.size(), 10u);
  ASSERT_EQ(cold.size(), none.size());
  ASSERT_EQ(warm.size(), none.size());
  for (const auto& [path, bytes] : none) {
    SCOPED_TRACE(path);
    ASSERT_TRUE(cold.count(path) && warm.count(path));
    EXPECT_TRUE(cold.at(path) == warm.at(path));
    if (!is_record(path)) {
      EXPECT_TRUE(cold.at(path) == bytes);
    }
  }

  const std::string stored = read_file(entries[0]);
  write_text_file(entries[0], stored.substr(0, stored.size() - 100));
  const auto [damaged_summary, damaged] = run("damaged", cache);
  EXPECT_TRUE(contains(damaged_summary.stages[1].modelled, "a damaged body mesh cache entry"));
  EXPECT_TRUE(damaged_summary.stages[1].warnings.empty()); // meshed again soundly: nothing for --strict
  for (const auto& [path, bytes] : none) {
    if (!is_record(path)) {
      EXPECT_TRUE(damaged.at(path) == bytes) << path;
    }
  }
  EXPECT_TRUE(read_file(entries[0]) == stored);
}

// What the deformation stage names as a body mesh's inputs (beside the anatomy's key) changes
// with what shapes the mesh and with nothing else: a load's volume change or a material's
// stiffness leave it as it is; a nested organ given its holder's material under
// anatomy.tet_interfaces: materials (one region fewer) or another seed change it. The source
// stops the stage once it has the inputs (no mesh, no solve).
TEST(BodyMeshCache, TheInputsChangeWithTheMeshsRegionsAndSeedOnly) {
  struct Stop {};
  Scene scene = scene_of(k_balls);
  scene.anatomy.tet_interfaces = TetInterfaces::materials;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  const auto inputs_of = [&](const std::function<void(DeformationSettings&, Phantom&)>& change) {
    DeformationSettings deformation = scene.deformation;
    Phantom changed = phantom;
    change(deformation, changed);
    std::string inputs;
    const BodyMeshSource record = [&](const std::string& text,
                                      const std::function<NestedBodyMesh()>&) -> NestedBodyMesh {
      inputs = text;
      throw Stop{};
    };
    StageReport report;
    EXPECT_THROW(deform_phantom(deformation, scene.organs, changed, report, quiet, record), Stop);
    return inputs;
  };
  const std::string base = inputs_of([](DeformationSettings&, Phantom&) {});
  EXPECT_NE(base.find("regions"), std::string::npos) << base;
  EXPECT_EQ(inputs_of([](DeformationSettings& d, Phantom&) { d.loads[0].volume_change = -0.2; }), base);
  EXPECT_EQ(inputs_of([](DeformationSettings& d, Phantom&) { d.materials[1].youngs_modulus_Pa *= 2; }), base);
  const std::string merged =
      inputs_of([](DeformationSettings& d, Phantom&) { d.organs[3].material = "fluid"; });
  EXPECT_NE(merged, base);
  EXPECT_LT(merged.size(), base.size()); // the right ball is no region of its own
  EXPECT_NE(inputs_of([](DeformationSettings&, Phantom& p) { p.seed += 1; }), base);
}
