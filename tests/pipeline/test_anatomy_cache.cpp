// The anatomy cache (pipeline/anatomy_cache.hpp): what it reads back is the built phantom bit for
// bit, every setting and input reaches its key, and a damaged entry is built again.

#include "anatomy/phantom.hpp"
#include "io/shape_files.hpp"
#include "pipeline/anatomy_cache.hpp"
#include "scene/scene.hpp"
#include "tests/pipeline/cache_fixtures.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <set>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_source = PHANTASM_SOURCE_DIR;

} // namespace

// Patch surfaces with bumps and a CGAL solid (small head), a structured box (bar) and a sheet
// (cloth): decoded, each is the built phantom, and its encoding the same bytes.
TEST(AnatomyCache, DecodedGeometryIsTheBuiltPhantomBitForBit) {
  for (const fs::path& file :
       {k_source / "tests" / "data" / "scenes" / "small-head.yaml", k_source / "data-synthetic" / "bar.yaml",
        k_source / "data-synthetic" / "cloth.yaml"}) {
    SCOPED_TRACE(file.string());
    const Scene scene = scene_of(file);
    const auto files = read_shape_files(scene.anatomy);
    Reporter built_log = Reporter::silent(), read_log = Reporter::silent();
    const Phantom built = build_phantom(scene.anatomy, files, built_log);
    const std::string bytes = encode_organ_geometry(built);
    const Phantom read = phantom_from_geometry(scene.anatomy, files, bytes, read_log);
    EXPECT_TRUE(encode_organ_geometry(read) == bytes);
    EXPECT_EQ(read_log.log_lines(), built_log.log_lines());
    ASSERT_EQ(read.organs.size(), built.organs.size());
    for (std::size_t o = 0; o < built.organs.size(); ++o) {
      const Organ& a = built.organs[o];
      const Organ& b = read.organs[o];
      SCOPED_TRACE(a.name);
      EXPECT_EQ(a.name, b.name);
      EXPECT_EQ(a.tissue, b.tissue);
      ASSERT_EQ(a.target == nullptr, b.target == nullptr); // a sheet has none
      if (a.target) {
        EXPECT_EQ(a.target->volume(), b.target->volume());
      }
      ASSERT_EQ(a.surface.has_value(), b.surface.has_value());
      if (a.surface) {
        EXPECT_EQ(a.surface->base_mesh().vertices, b.surface->base_mesh().vertices);
        EXPECT_EQ(a.surface->volume(), b.surface->volume()); // the bumps' perturbations too
        const Eigen::Vector3d probe = a.surface->base_mesh().vertex(0) * 0.9;
        EXPECT_EQ(a.surface->value(0, probe), b.surface->value(0, probe));
        // The patches' height bounds: held by the built anatomy, stored and read back.
        ASSERT_NE(a.surface->height_ranges(), nullptr);
        ASSERT_NE(b.surface->height_ranges(), nullptr);
        const std::vector<HeightRange> computed = patch_height_ranges(*a.surface);
        ASSERT_EQ(b.surface->height_ranges()->size(), computed.size());
        for (std::size_t t = 0; t < computed.size(); ++t) {
          EXPECT_EQ((*a.surface->height_ranges())[t].lowest, computed[t].lowest);
          EXPECT_EQ((*b.surface->height_ranges())[t].lowest, computed[t].lowest);
          EXPECT_EQ((*b.surface->height_ranges())[t].highest, computed[t].highest);
        }
      }
      ASSERT_EQ(a.solid.has_value(), b.solid.has_value());
      if (a.solid) {
        EXPECT_EQ(a.solid->vertices, b.solid->vertices);
        EXPECT_EQ(a.solid->tets, b.solid->tets);
      }
      ASSERT_EQ(a.sheet.has_value(), b.sheet.has_value());
      EXPECT_EQ(a.tet_vertex_of_surface_vertex, b.tet_vertex_of_surface_vertex);
      EXPECT_EQ(a.fit.source_max_mm, b.fit.source_max_mm);
      EXPECT_EQ(a.fit.source_mean_mm, b.fit.source_mean_mm);
    }
    // Bytes cut short or of other organs are refused, not misread.
    EXPECT_THROW(phantom_from_geometry(scene.anatomy, files, bytes.substr(0, bytes.size() / 2), read_log),
                 DamagedGeometry);
    AnatomySettings renamed = scene.anatomy;
    renamed.organs[0].name += "x";
    EXPECT_THROW(phantom_from_geometry(renamed, files, bytes, read_log), DamagedGeometry);
  }
}

// A change of any setting the anatomy reads, or of a file's bytes, gives another key.
TEST(AnatomyCache, EverySettingAndInputChangesTheKey) {
  const Scene scene = scene_of(k_source / "tests" / "data" / "scenes" / "small-head.yaml");
  std::map<std::string, ShapeData> files;
  ShapeData labels;
  labels.label_grid = scene.grid.grid();
  labels.labels = std::make_shared<const std::vector<std::int32_t>>(8, 1);
  labels.target_labels = {1};
  labels.source = "labels.nii.gz";
  files["scalp"] = labels;
  using Change = std::function<void(AnatomySettings&, std::map<std::string, ShapeData>&)>;
  const std::vector<Change> changes = {
      [](AnatomySettings& a, auto&) { a.variation += 0.01; },
      [](AnatomySettings& a, auto&) { a.base_mesh_triangles += 1; },
      [](AnatomySettings& a, auto&) { a.tet_size_mm += 1.0; },
      [](AnatomySettings& a, auto&) { a.tet_facet_distance_mm += 1.0; },
      [](AnatomySettings& a, auto&) { a.tet_interfaces = TetInterfaces::materials; },
      [](AnatomySettings& a, auto&) { a.seed += 1; },
      [](AnatomySettings& a, auto&) { a.organs.pop_back(); },
      [](AnatomySettings& a, auto&) { a.organs[1].name += "x"; },
      [](AnatomySettings& a, auto&) { a.organs[1].tissue += "x"; },
      [](AnatomySettings& a, auto&) { a.organs[1].material += "x"; },
      [](AnatomySettings& a, auto&) { a.organs[2].inside += "x"; },
      [](AnatomySettings& a, auto&) { a.organs[1].solid = !a.organs[1].solid; },
      [](AnatomySettings& a, auto&) { a.organs[1].base_mesh_triangles += 1; },
      [](AnatomySettings& a, auto&) { a.organs[1].thickness_mm *= 2.0; },
      [](AnatomySettings& a, auto&) { a.organs[1].enclosed_volume_tolerance = 0.01; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.kind = ShapeKind::superquadric; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.center_mm.x() += 1e-9; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.radii_mm.z() += 1e-9; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.rotation_deg.y() += 1.0; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.exponent_1 += 0.1; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.exponent_2 += 0.1; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.size_mm.x() += 1.0; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.cells.x() += 1; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.file = "other.obj"; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.atlas = "colin27"; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.label = 7; },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.labels.push_back("caudate"); },
      [](AnatomySettings& a, auto&) { a.organs[1].shape.smoothing_mm = 1.0; },
      [](auto&, std::map<std::string, ShapeData>& f) {
        f["scalp"].labels = std::make_shared<const std::vector<std::int32_t>>(
            std::vector<std::int32_t>{1, 1, 1, 1, 1, 1, 1, 2});
      },
      [](auto&, std::map<std::string, ShapeData>& f) { f["scalp"].target_labels.push_back(2); },
      [](auto&, std::map<std::string, ShapeData>& f) { f["scalp"].label_grid->spacing_mm.x() *= 2.0; },
      [](auto&, std::map<std::string, ShapeData>& f) {
        ShapeData mesh;
        mesh.mesh.emplace();
        mesh.mesh->vertices = Eigen::MatrixX3d::Zero(3, 3);
        mesh.mesh->faces = Eigen::MatrixX3i::Zero(1, 3);
        f["grey_matter"] = mesh;
      },
  };
  const std::string base = anatomy_cache_key(scene.anatomy, files);
  ASSERT_EQ(base.size(), 64u) << "no build id: the cache would be off";
  EXPECT_EQ(anatomy_cache_key(scene.anatomy, files), base);
  std::set<std::string> keys{base};
  for (std::size_t c = 0; c < changes.size(); ++c) {
    AnatomySettings anatomy = scene.anatomy;
    auto changed_files = files;
    changes[c](anatomy, changed_files);
    EXPECT_TRUE(keys.insert(anatomy_cache_key(anatomy, changed_files)).second) << "change " << c;
  }
}

// Stored once, read by the next run (the same phantom), built again when the entry is damaged;
// the log line is the same whether the run built the entry or read it.
TEST(AnatomyCache, StoresReadsAndRebuildsADamagedEntry) {
  const Scene scene = scene_of(k_source / "tests" / "data" / "scenes" / "small-head.yaml");
  const auto files = read_shape_files(scene.anatomy);
  const fs::path folder = fresh_folder("anatomy-cache");
  const auto run = [&](StageReport& report) {
    Reporter reporter = Reporter::silent();
    return encode_organ_geometry(build_phantom_cached(scene.anatomy, files, folder, report, reporter));
  };
  StageReport first, second, third;
  const std::string built = run(first);
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".bin") entries.push_back(entry.path());
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_NE(entries[0].filename().string().find(anatomy_cache_key(scene.anatomy, files)), std::string::npos);
  EXPECT_TRUE(run(second) == built);
  EXPECT_EQ(second.modelled, first.modelled);
  EXPECT_TRUE(contains(first.modelled, "kept in the anatomy cache as entry"));

  std::string bytes = read_file(entries[0]);
  write_text_file(entries[0], bytes.substr(0, bytes.size() - 100));
  EXPECT_TRUE(run(third) == built);
  EXPECT_TRUE(contains(third.modelled, "a damaged anatomy cache entry")) << third.modelled.size();
  EXPECT_TRUE(third.warnings.empty()); // the anatomy built again is sound: --strict has nothing to refuse
  EXPECT_TRUE(read_file(entries[0]) == bytes);
}
